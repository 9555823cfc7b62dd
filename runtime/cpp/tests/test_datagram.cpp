// Datagram transports: the shared vectors contracts/vectors/link/datagram.json (written
// by the Python codec) verified and re-encoded byte for byte by the C++ codec;
// forged, reflected, replayed and corrupt datagrams are refused.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "modd/link/datagram.hpp"
#include "modd/util/bytes.hpp"
#include "modd/util/error.hpp"

using namespace modd;
using namespace modd::link;
using namespace modd::link::dgram;
using nlohmann::json;

namespace {

json vectors() {
  std::ifstream f(std::string(MODD_VECTORS_DIR) + "/datagram.json");
  EXPECT_TRUE(f.good());
  return json::parse(f);
}

Mac key_of(const json& v) {
  auto k = from_hex(v["session_key"].get<std::string>());
  Mac m{};
  std::copy(k.begin(), k.end(), m.begin());
  return m;
}

const json& by_name(const json& v, const std::string& name) {
  for (const auto& c : v["vectors"])
    if (c["name"] == name) return c;
  throw std::runtime_error("no vector " + name);
}

uint8_t dir(const json& c) { return c["direction"] == "D" ? kDroneToBase : kBaseToDrone; }

}  // namespace

TEST(Datagram, SessionKeyFromHandshakeNonces) {
  auto v = vectors();
  auto psk = from_hex(v["key"].get<std::string>());
  Nonce cn{}, sn{};
  auto c = from_hex(v["client_nonce"].get<std::string>());
  auto s = from_hex(v["server_nonce"].get<std::string>());
  std::copy(c.begin(), c.end(), cn.begin());
  std::copy(s.begin(), s.end(), sn.begin());
  EXPECT_EQ(session_key(psk, cn, sn), key_of(v));
}

TEST(Datagram, DataVectorsVerifyAndEncodeBack) {
  auto v = vectors();
  Mac key = key_of(v);
  for (std::string name : {"data_scenario1_5_slots", "data_bitmap"}) {
    const auto& c = by_name(v, name);
    auto raw = from_hex(c["hex"].get<std::string>());
    auto got = verify_data(raw, key, dir(c), c["expected_slot"].get<uint64_t>());
    EXPECT_EQ(got.slot, c["slot"].get<uint64_t>()) << name;
    EXPECT_EQ(got.config_id, c["config_id"].get<uint8_t>());
    DataDatagram d{got.config_id, got.slot, {}, {}};
    std::vector<uint8_t> all;
    for (const auto& s : c["slots"]) {
      d.slots.push_back(from_hex(s.get<std::string>()));
      all.insert(all.end(), d.slots.back().begin(), d.slots.back().end());
    }
    EXPECT_EQ(got.values, all);
    if (c.contains("presence")) {
      for (bool p : c["presence"]) d.presence.push_back(p);
      EXPECT_EQ(got.slot_count.value(), d.slots.size());
    }
    EXPECT_EQ(to_hex(encode_data(d, key, dir(c))), c["hex"].get<std::string>()) << name;
  }
}

TEST(Datagram, ControlVectors) {
  auto v = vectors();
  Mac key = key_of(v);
  for (std::string name : {"control_nack", "control_ping"}) {
    const auto& c = by_name(v, name);
    auto raw = from_hex(c["hex"].get<std::string>());
    auto [counter, frame] = verify_control(raw, key, dir(c));
    EXPECT_EQ(counter, c["counter"].get<uint64_t>());
    EXPECT_EQ(to_hex(encode_control(counter, frame, key, dir(c))), c["hex"].get<std::string>());
  }
}

TEST(Datagram, SerialFrameVector) {
  auto v = vectors();
  const auto& c = by_name(v, "serial_data_scenario1_5_slots");
  auto datagram = from_hex(c["datagram"].get<std::string>());
  EXPECT_EQ(to_hex(encode_frame(datagram)), c["hex"].get<std::string>());
  Deframer df(252);
  auto got = df.feed(from_hex(c["hex"].get<std::string>()));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], datagram);
  const uint8_t check[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(crc16(check), 0x29B1);
}

TEST(Datagram, InvalidVectorsAreRefused) {
  auto v = vectors();
  Mac key = key_of(v);
  for (const auto& c : v["invalid"]) {
    if (c.contains("kind")) continue;  // fragments: InvalidFragmentsAreRefused
    auto raw = from_hex(c["hex"].get<std::string>());
    uint64_t expected = c["expected_slot"].get<uint64_t>();
    if (c["name"] == "replay") {
      ReplayWindow w;
      EXPECT_TRUE(w.accept(verify_data(raw, key, dir(c), expected).slot));
      EXPECT_FALSE(w.accept(verify_data(raw, key, dir(c), expected).slot));
      continue;
    }
    EXPECT_THROW(verify_data(raw, key, dir(c), expected), Forged) << c["name"];
  }
}

TEST(Datagram, RandomBytesNeverVerify) {
  Mac key{};
  std::mt19937 rng(14);
  for (int i = 0; i < 5000; ++i) {
    std::vector<uint8_t> raw(rng() % 80);
    for (auto& b : raw) b = static_cast<uint8_t>(rng());
    try {
      verify_data(raw, key, kDroneToBase, 70000);
      ADD_FAILURE() << "random bytes verified: " << to_hex(raw);
    } catch (const Forged&) {
    } catch (const Error& e) { EXPECT_EQ(e.code(), ErrorCode::BadFrame); }
  }
}

TEST(Datagram, Extend16AndReplayWindow) {
  EXPECT_EQ(extend16(0xFFFF, 0x10002), 0xFFFFu);
  EXPECT_EQ(extend16(2, 0xFFFE), 0x10002u);
  EXPECT_EQ(extend16(5, 0), 5u);
  ReplayWindow w(8);
  EXPECT_TRUE(w.accept(10));
  EXPECT_TRUE(w.accept(12));
  EXPECT_TRUE(w.accept(11));
  EXPECT_FALSE(w.accept(11));
  EXPECT_TRUE(w.accept(30));
  EXPECT_FALSE(w.accept(22));
  EXPECT_TRUE(w.accept(23));
}

TEST(Datagram, FragmentVectorsVerifyAndEncodeBack) {
  auto v = vectors();
  Mac key = key_of(v);
  const auto& c = by_name(v, "fragments_of_one_slot");
  std::vector<bool> presence;
  for (bool p : c["presence"]) presence.push_back(p);
  auto body = slot_bitmap_body(presence, from_hex(c["values"].get<std::string>()));
  EXPECT_EQ(to_hex(body), c["body"].get<std::string>());
  auto frags = encode_fragments(1, c["slot"].get<uint64_t>(), body, c["max_datagram"].get<size_t>(),
                                key, kDroneToBase);
  ASSERT_EQ(frags.size(), c["fragments"].size());
  std::vector<uint8_t> whole;
  for (size_t i = 0; i < frags.size(); ++i) {
    EXPECT_EQ(to_hex(frags[i]), c["fragments"][i].get<std::string>()) << i;
    auto f = verify_fragment(frags[i], key, kDroneToBase, c["expected_slot"].get<uint64_t>());
    EXPECT_EQ(f.slot, c["slot"].get<uint64_t>());
    EXPECT_EQ(f.index, i);
    EXPECT_EQ(f.count, frags.size());
    whole.insert(whole.end(), f.piece.begin(), f.piece.end());
  }
  EXPECT_EQ(whole, body);
  EXPECT_THROW(encode_fragments(1, 5, std::vector<uint8_t>(17 * 11), 20, key, kDroneToBase),
               std::invalid_argument);
}

TEST(Datagram, InvalidFragmentsAreRefused) {
  auto v = vectors();
  Mac key = key_of(v);
  int seen = 0;
  for (const auto& c : v["invalid"]) {
    if (!c.contains("kind") || c["kind"] != "fragment") continue;
    ++seen;
    auto raw = from_hex(c["hex"].get<std::string>());
    uint64_t expected = c["expected_slot"].get<uint64_t>();
    if (c["name"] == "fragment_forged") {
      EXPECT_THROW(verify_fragment(raw, key, dir(c), expected), Forged);
    } else {
      try {
        verify_fragment(raw, key, dir(c), expected);
        ADD_FAILURE() << c["name"];
      } catch (const Error& e) { EXPECT_EQ(e.code(), ErrorCode::BadFrame); }
    }
  }
  EXPECT_EQ(seen, 2);
}

TEST(Datagram, ControlFragmentVectorsVerifyAndEncodeBack) {
  auto v = vectors();
  Mac key = key_of(v);
  const auto& c = by_name(v, "control_fragments_of_a_config");
  auto frames = from_hex(c["frames"].get<std::string>());
  uint64_t counter = c["counter"].get<uint64_t>();
  auto frags =
      encode_control_fragments(counter, frames, c["max_datagram"].get<size_t>(), key, kBaseToDrone);
  ASSERT_EQ(frags.size(), c["fragments"].size());
  ASSERT_GT(frags.size(), 1u);
  ControlPieces pieces;
  std::optional<std::vector<uint8_t>> whole;
  for (size_t k = frags.size(); k-- > 0;) {  // in reverse order
    EXPECT_EQ(to_hex(frags[k]), c["fragments"][k].get<std::string>()) << k;
    EXPECT_LE(frags[k].size(), c["max_datagram"].get<size_t>());
    auto f = verify_control_fragment(frags[k], key, kBaseToDrone);
    EXPECT_EQ(f.counter, counter + k);
    EXPECT_EQ(f.index, k);
    EXPECT_EQ(f.first(), counter);
    EXPECT_EQ(f.count, frags.size());
    EXPECT_FALSE(whole.has_value());
    whole = pieces.add(std::move(f));
  }
  ASSERT_TRUE(whole.has_value());
  EXPECT_EQ(*whole, frames);
  EXPECT_THROW(encode_control_fragments(1, std::vector<uint8_t>(17 * 10), 25, key, kBaseToDrone),
               std::invalid_argument);
}

TEST(Datagram, InvalidControlFragmentsAreRefused) {
  auto v = vectors();
  Mac key = key_of(v);
  int seen = 0;
  for (const auto& c : v["invalid"]) {
    if (!c.contains("kind") || c["kind"] != "control_fragment") continue;
    ++seen;
    auto raw = from_hex(c["hex"].get<std::string>());
    if (c["name"] == "control_fragment_forged") {
      EXPECT_THROW(verify_control_fragment(raw, key, dir(c)), Forged);
    } else {
      try {
        verify_control_fragment(raw, key, dir(c));
        ADD_FAILURE() << c["name"];
      } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::BadFrame);
        EXPECT_EQ(e.offset(), 3u);
      }
    }
  }
  EXPECT_EQ(seen, 2);
}

TEST(Datagram, ControlPiecesAreBoundedAndRefuseAChangedCount) {
  Mac key{};
  std::vector<uint8_t> frames(200);
  for (size_t i = 0; i < frames.size(); ++i) frames[i] = static_cast<uint8_t>(i);
  ControlPieces pieces;
  std::vector<std::vector<std::vector<uint8_t>>> messages;
  for (uint64_t k = 1; k <= 6; ++k)
    messages.push_back(encode_control_fragments(100 * k, frames, 60, key, kBaseToDrone));
  for (auto& m : messages)
    EXPECT_FALSE(pieces.add(verify_control_fragment(m[0], key, kBaseToDrone)));
  EXPECT_EQ(pieces.given_up(), 2u);                // the oldest two
  for (size_t i = 1; i < messages[0].size(); ++i)  // the rest of a message given up: never whole
    EXPECT_FALSE(pieces.add(verify_control_fragment(messages[0][i], key, kBaseToDrone)));
  std::optional<std::vector<uint8_t>> done;
  for (size_t i = 1; i < messages[5].size(); ++i)
    done = pieces.add(verify_control_fragment(messages[5][i], key, kBaseToDrone));
  ASSERT_TRUE(done.has_value());
  EXPECT_EQ(*done, frames);
  auto other = encode_control_fragments(500, std::vector<uint8_t>(300), 60, key, kBaseToDrone);
  EXPECT_FALSE(pieces.add(verify_control_fragment(other[1], key, kBaseToDrone)));
  EXPECT_EQ(pieces.malformed(), 1u);  // message 500 has 5 pieces, this one says 7
}
