// The PubBroker's datagram session without sockets: handshake in datagrams
// (a repeated HELLO gets the same CHALLENGE), CONFIG applied once however
// often it is resent, slots packed up to the accepted delay, a NACK answered
// from the ring (tagged again under a new session), forged and replayed
// control datagrams dropped and counted, the keepalive timeout.
#include <gtest/gtest.h>

#include <optional>

#include "modd/broker/dgram_link.hpp"
#include "modd/link/auth.hpp"
#include "modd/link/backfill.hpp"
#include "modd/link/codec.hpp"
#include "modd/link/datagram.hpp"

using namespace modd;
using namespace modd::broker;
using namespace modd::link;
namespace dg = modd::link::dgram;

namespace {

struct Hooks : LinkHooks {
  int configs = 0, auths = 0, rejects = 0;
  ConfigAck on_config(const Config& c) override {
    ++configs;
    return {c.config_id, 0, 77};
  }
  AuthOk current_config() override { return AuthOk{{}, 0, 0}; }
  void on_authenticated() override { ++auths; }
  void on_rejected(const std::string&) override { ++rejects; }
  std::vector<uint8_t> backfill_reply;  // what a backfill request is answered with
  void on_backfill(const RawFrame&, std::vector<uint8_t>& out) override {
    out.insert(out.end(), backfill_reply.begin(), backfill_reply.end());
  }
};

struct Out : DatagramOut {
  std::vector<std::vector<uint8_t>> sent;
  int adopted = 0;
  void send(std::vector<uint8_t>&& d, bool) override { sent.push_back(std::move(d)); }
  void adopt_source() override { ++adopted; }
};

const std::string kPsk = "psk";
std::span<const uint8_t> psk() {
  return {reinterpret_cast<const uint8_t*>(kPsk.data()), kPsk.size()};
}

template <typename T>
std::vector<uint8_t> hs(const T& m) {
  std::vector<uint8_t> d{dg::kHandshake};
  encode(d, m);
  return d;
}

Message answer(const std::vector<uint8_t>& d) {
  auto f = split_frame(std::span(d).subspan(1));
  return decode(*f);
}

struct Session {
  Hooks hooks;
  Out out;
  DatagramLink link{kPsk, hooks, out, DgramOptions{200, 1'000'000'000, 5'000'000'000, 256, 65536},
                    Mac{}};
  Mac key{};
  uint64_t counter = 0;

  void handshake(uint8_t client_byte, int64_t now) {
    Nonce c{};
    c.fill(client_byte);
    link.on_datagram(hs(Hello{kVersion, c}), now);
    auto ch = std::get<Challenge>(answer(out.sent.back()));
    link.on_datagram(hs(Auth{client_proof(psk(), c, ch.nonce)}), now);
    auto ok = std::get<AuthOk>(answer(out.sent.back()));
    ASSERT_TRUE(macs_equal(ok.mac, server_proof(psk(), c, ch.nonce)));
    key = dg::session_key(psk(), c, ch.nonce);
  }
  std::vector<uint8_t> control(const std::vector<uint8_t>& frame) {
    return dg::encode_control(++counter, frame, key, dg::kBaseToDrone);
  }
};

std::vector<uint8_t> nack(uint64_t first, uint64_t n) {
  std::vector<uint8_t> body{1};
  for (uint64_t v : {first, n}) {
    while (v >= 0x80) {
      body.push_back(static_cast<uint8_t>(v | 0x80));
      v >>= 7;
    }
    body.push_back(static_cast<uint8_t>(v));
  }
  std::vector<uint8_t> f{static_cast<uint8_t>(body.size() + 1), 0x09};
  f.insert(f.end(), body.begin(), body.end());
  return f;
}

}  // namespace

TEST(DgramLink, RepeatedHelloGetsTheSameChallengeAndAuthOpensTheSession) {
  Session s;
  Nonce c{};
  c.fill(9);
  s.link.on_datagram(hs(Hello{kVersion, c}), 0);
  s.link.on_datagram(hs(Hello{kVersion, c}), 1);
  EXPECT_EQ(std::get<Challenge>(answer(s.out.sent[0])).nonce,
            std::get<Challenge>(answer(s.out.sent[1])).nonce);
  EXPECT_FALSE(s.link.ready());
  s.link.on_datagram(hs(Auth{Mac{}}), 2);  // a wrong proof
  EXPECT_FALSE(s.link.ready());
  EXPECT_EQ(s.hooks.rejects, 1);
  s.handshake(9, 3);
  EXPECT_TRUE(s.link.ready());
  EXPECT_EQ(s.hooks.auths, 1);
}

TEST(DgramLink, ConfigAppliedOnceThoughResent) {
  Session s;
  s.handshake(1, 0);
  Config cfg;
  cfg.config_id = 3;
  std::vector<uint8_t> frame;
  encode(frame, Message{cfg});
  s.link.on_datagram(s.control(frame), 1);
  s.link.on_datagram(s.control(frame), 2);  // its ack was lost
  EXPECT_EQ(s.hooks.configs, 1);
  for (size_t i : {s.out.sent.size() - 2, s.out.sent.size() - 1}) {
    auto [counter, f] = dg::verify_control(s.out.sent[i], s.key, dg::kDroneToBase);
    EXPECT_EQ(std::get<ConfigAck>(decode(*split_frame(f))).epoch_ns, 77u);
  }
}

TEST(DgramLink, PacksSlotsUpToTheDelayAndResendsOnNack) {
  Session s;
  s.handshake(1, 0);
  size_t before = s.out.sent.size();
  const int64_t q = 250'000'000;
  for (uint64_t k = 0; k < 8; ++k) {
    s.link.add_slot(1, k, static_cast<int64_t>(k + 1) * q, {1, 2, 3, 4}, {true});
    s.link.tick(static_cast<int64_t>(k + 1) * q);
  }
  // slots 0..4 (0.25 .. 1.25 s) in one datagram, sent at 1.25 s; 5..7 wait
  ASSERT_EQ(s.out.sent.size(), before + 1);
  auto v = dg::verify_data(s.out.sent.back(), s.key, dg::kDroneToBase, 0);
  EXPECT_EQ(v.slot, 0u);
  EXPECT_EQ(v.values.size(), 5u * 4);
  s.link.tick(9 * q);  // nothing due yet
  ASSERT_EQ(s.out.sent.size(), before + 1);
  s.link.tick(10 * q);  // slot 5 (1.5 s) waited 1 s
  ASSERT_EQ(s.out.sent.size(), before + 2);
  auto first = s.out.sent[before];
  // a new session, then a NACK of slot 2: the datagram of slots 0..4, tagged under the new key
  s.handshake(2, 11 * q);
  s.link.on_datagram(s.control(nack(2, 1)), 11 * q);
  auto resent = s.out.sent.back();
  EXPECT_NE(resent, first);
  EXPECT_EQ(dg::verify_data(resent, s.key, dg::kDroneToBase, 0).values, v.values);
  EXPECT_EQ(s.link.counters().resent, 1u);
}

TEST(DgramLink, ANackOfAConfigThatReusesAnIdIsNotAnsweredWithTheOlderConfigsSlots) {
  // Config 1 ran (another station's), then config 2, then a restarted SubBroker's
  // config 1 again, its slots from 0: a NACK names slots alone, so slot 1 of the new
  // config 1 must come back as the new one's, never as the older config 1's slot 1.
  Session s;
  s.handshake(1, 0);
  const int64_t q = 250'000'000, ms = 1'000'000;
  auto run = [&](uint8_t id, uint8_t value, int64_t from) {  // within the keepalive (5 s)
    for (uint64_t k = 0; k < 4; ++k)
      s.link.add_slot(id, k, from + static_cast<int64_t>(k + 1) * q, {value, value}, {true});
    s.link.tick(from + 1400 * ms);  // the group of 4 slots waited its accepted delay
    return s.out.sent.back();
  };
  run(1, 10, 0);
  run(2, 20, 1500 * ms);
  auto renewed = run(1, 30, 3000 * ms);
  auto v = dg::verify_data(renewed, s.key, dg::kDroneToBase, 0);
  ASSERT_EQ(v.config_id, 1);
  size_t before = s.out.sent.size();
  s.link.on_datagram(s.control(nack(1, 1)), 4500 * ms);
  // config 2's datagram covers slot 1 too (the base station drops it: another config)
  std::vector<std::vector<uint8_t>> config1;
  for (size_t i = before; i < s.out.sent.size(); ++i) {
    auto r = dg::verify_data(s.out.sent[i], s.key, dg::kDroneToBase, 0);
    if (r.config_id == 1) config1.push_back(r.values);
  }
  ASSERT_EQ(config1.size(), 1u) << "the older config 1's datagram answered the NACK too";
  EXPECT_EQ(config1[0], v.values);
}

TEST(DgramLink, AConfigChangesTheAcceptedDelayAndAnOldOneRestoresIt) {
  Session s;
  s.handshake(1, 0);
  const int64_t q = 250'000'000;
  auto send_config = [&](uint8_t id, std::optional<uint32_t> delay_ms, int64_t now) {
    Config cfg;
    cfg.config_id = id;
    cfg.accepted_delay_ms = delay_ms;
    std::vector<uint8_t> frame;
    encode(frame, Message{cfg});
    s.link.on_datagram(s.control(frame), now);
  };
  send_config(2, 250, 1);
  EXPECT_EQ(s.link.delay_ns(), q);
  size_t before = s.out.sent.size();
  for (uint64_t k = 0; k < 4; ++k) {
    s.link.add_slot(2, k, static_cast<int64_t>(k + 1) * q, {1, 2, 3, 4}, {true});
    s.link.tick(static_cast<int64_t>(k + 1) * q);
  }
  // up to 0.25 s: slots 0, 1 (0.25, 0.5 s) sent at 0.5 s, slots 2, 3 at 1 s
  ASSERT_EQ(s.out.sent.size(), before + 2);
  EXPECT_EQ(dg::verify_data(s.out.sent[before], s.key, dg::kDroneToBase, 0).values.size(), 2u * 4);
  EXPECT_EQ(dg::verify_data(s.out.sent[before + 1], s.key, dg::kDroneToBase, 2).slot, 2u);
  send_config(3, std::nullopt, 5 * q);  // no field: the config file's delay again
  EXPECT_EQ(s.link.delay_ns(), 1'000'000'000);
  send_config(4, 0, 6 * q);  // 0: one slot a datagram
  EXPECT_EQ(s.link.delay_ns(), 0);
}

TEST(DgramLink, ForgedAndReplayedControlDatagramsAreDroppedAndCounted) {
  Session s;
  s.handshake(1, 0);
  std::vector<uint8_t> ping;
  encode(ping, Message{Ping{{1, 2}}});
  auto good = s.control(ping);
  auto bad = good;
  bad[3] ^= 0x20;
  size_t before = s.out.sent.size();
  s.link.on_datagram(bad, 1);
  s.link.on_datagram(good, 2);
  s.link.on_datagram(good, 3);  // replayed
  EXPECT_EQ(s.link.counters().forged, 1u);
  EXPECT_EQ(s.link.counters().replayed, 1u);
  EXPECT_EQ(s.out.sent.size(), before + 1);  // one PONG
}

TEST(DgramLink, SilenceStopsDataUntilANewHandshake) {
  Session s;
  s.handshake(1, 0);
  s.link.tick(5'000'000'001);
  EXPECT_FALSE(s.link.ready());
  EXPECT_FALSE(s.link.add_slot(1, 0, 6'000'000'000, {1}, {true}));
  s.handshake(3, 7'000'000'000);
  EXPECT_TRUE(s.link.ready());
}

TEST(DgramLink, ASlotLargerThanThePacketGoesAsFragmentsAndIsResentWhole) {
  Session s;  // max_datagram 200
  s.handshake(1, 0);
  const int64_t q = 250'000'000;
  s.link.add_slot(1, 0, q, {1, 2, 3}, {true});
  size_t before = s.out.sent.size();
  std::vector<uint8_t> big(450);
  for (size_t i = 0; i < big.size(); ++i) big[i] = static_cast<uint8_t>(i * 7);
  s.link.add_slot(1, 1, 2 * q, std::vector<uint8_t>(big), {true, false, true});
  // slot 0's group goes first, then the 3 fragments of slot 1, each within the packet
  ASSERT_EQ(s.out.sent.size(), before + 4);
  EXPECT_EQ(dg::verify_data(s.out.sent[before], s.key, dg::kDroneToBase, 0).slot, 0u);
  std::vector<uint8_t> whole;
  for (size_t i = before + 1; i < s.out.sent.size(); ++i) {
    EXPECT_LE(s.out.sent[i].size(), 200u);
    auto f = dg::verify_fragment(s.out.sent[i], s.key, dg::kDroneToBase, 0);
    EXPECT_EQ(f.slot, 1u);
    EXPECT_EQ(f.count, 3);
    whole.insert(whole.end(), f.piece.begin(), f.piece.end());
  }
  EXPECT_EQ(whole, dg::slot_bitmap_body({true, false, true}, big));
  EXPECT_EQ(s.link.counters().fragments, 3u);
  // a NACK of slot 1 resends its three fragments; after a new session, tagged under its key
  s.handshake(2, 3 * q);
  size_t mark = s.out.sent.size();
  s.link.on_datagram(s.control(nack(1, 1)), 4 * q);
  ASSERT_EQ(s.out.sent.size(), mark + 3);
  for (size_t i = mark; i < s.out.sent.size(); ++i)
    EXPECT_EQ(dg::verify_fragment(s.out.sent[i], s.key, dg::kDroneToBase, 0).slot, 1u);
  // a slot 16 fragments cannot hold is dropped and counted, and does not stop the next
  s.link.add_slot(1, 2, 3 * q, std::vector<uint8_t>(17 * 200), {true});
  EXPECT_EQ(s.link.counters().dropped, 1u);
  EXPECT_TRUE(s.link.add_slot(1, 3, 4 * q, {9}, {true}));
}

// The overhead the backfill pace counts per frame, against what the codec and the serial
// framing really add to a frame of one packet (counters up to 2^28).
TEST(DgramLink, ControlFrameOverheadBoundsTheWire) {
  Mac key{};
  for (size_t n : {1u, 60u, 200u, 230u}) {
    std::vector<uint8_t> frame(n, 0x00);  // zeros: COBS's worst case
    for (uint64_t counter : {1ull, 1000ull, (1ull << 28) - 1}) {
      auto datagram = dg::encode_control(counter, frame, key, dg::kDroneToBase);
      size_t udp = datagram.size() - n + 28;
      EXPECT_LE(udp, control_frame_overhead(false)) << n << " " << counter;
      size_t serial = dg::encode_frame(datagram).size() - n;
      EXPECT_LE(serial, control_frame_overhead(true)) << n << " " << counter;
      if (counter == (1ull << 28) - 1) {  // the bound is reached: not a loose guess
        EXPECT_EQ(udp, control_frame_overhead(false));
        EXPECT_EQ(serial, control_frame_overhead(true));
      }
    }
  }
}

// A CONFIG larger than one packet arrives as control fragments (scenario 2's on a SiK
// radio): applied once every piece is there, in any order; a forged or replayed piece is
// counted and dropped; the retry (every piece again, new counters) gets the same ack.
TEST(DgramLink, AConfigCutIntoControlFragmentsIsAppliedOnce) {
  Session s;
  s.handshake(1, 0);
  Config cfg;
  cfg.config_id = 4;
  for (uint32_t i = 0; i < 20; ++i) {
    cfg.topics.push_back(
        TopicSpec{"usv.accelerometer.accel_" + std::to_string(i), ValueType::Float32, 28, 10'000});
    cfg.streams.push_back(StreamSpec{i, Aggregation::Average, 250'000});
  }
  std::vector<uint8_t> frame;
  encode(frame, Message{cfg});
  ASSERT_GT(frame.size(), 3 * 200u);
  auto pieces = dg::encode_control_fragments(s.counter + 1, frame, 200, s.key, dg::kBaseToDrone);
  s.counter += pieces.size();
  ASSERT_GE(pieces.size(), 4u);
  auto forged = pieces[1];
  forged[5] ^= 1;
  s.link.on_datagram(forged, 1);
  EXPECT_EQ(s.link.counters().forged, 1u);
  size_t before = s.out.sent.size();
  for (size_t k = pieces.size(); k-- > 1;) s.link.on_datagram(pieces[k], 2);
  EXPECT_EQ(s.hooks.configs, 0);     // piece 0 still missing
  s.link.on_datagram(pieces[2], 3);  // a replay
  EXPECT_EQ(s.link.counters().replayed, 1u);
  s.link.on_datagram(pieces[0], 4);
  EXPECT_EQ(s.hooks.configs, 1);
  ASSERT_EQ(s.out.sent.size(), before + 1);
  auto [c1, ack] = dg::verify_control(s.out.sent.back(), s.key, dg::kDroneToBase);
  EXPECT_EQ(std::get<ConfigAck>(decode(*split_frame(ack))).config_id, 4);
  // its ack lost: the SubBroker sends every piece again, under new counters
  auto again = dg::encode_control_fragments(s.counter + 1, frame, 200, s.key, dg::kBaseToDrone);
  s.counter += again.size();
  for (auto& p : again) s.link.on_datagram(p, 5);
  EXPECT_EQ(s.hooks.configs, 1);  // applied once
  auto [c2, ack2] = dg::verify_control(s.out.sent.back(), s.key, dg::kDroneToBase);
  EXPECT_EQ(ack2, ack);
}

// The PubBroker's own control message larger than one datagram (here a backfill END
// with a long reason) goes as control fragments, each within the packet.
TEST(DgramLink, ALargeControlMessageGoesAsControlFragments) {
  Session s;
  s.handshake(1, 0);
  namespace bf = modd::link::backfill;
  bf::End end{7, bf::EndStatus::Io, 0, std::string(450, 'x')};
  bf::encode(s.hooks.backfill_reply, bf::Message{end});
  std::vector<uint8_t> cancel;
  bf::encode(cancel, bf::Message{bf::Cancel{7}});
  size_t before = s.out.sent.size();
  s.link.on_datagram(s.control(cancel), 1);
  std::vector<std::vector<uint8_t>> frags(s.out.sent.begin() + static_cast<std::ptrdiff_t>(before),
                                          s.out.sent.end());
  ASSERT_GE(frags.size(), 3u);
  dg::ControlPieces pieces;
  std::optional<std::vector<uint8_t>> whole;
  for (auto& d : frags) {
    EXPECT_EQ(d[0], dg::kControlFragment);
    EXPECT_LE(d.size(), 200u);
    whole = pieces.add(dg::verify_control_fragment(d, s.key, dg::kDroneToBase));
  }
  ASSERT_TRUE(whole.has_value());
  EXPECT_EQ(std::get<bf::End>(bf::decode(*split_frame(*whole))), end);
}

// Declared resolution: a slot that joins the open datagram is written against its
// chain (deltas), one that starts a datagram against an empty chain; so each
// datagram decodes on its own, and a lost one corrupts no other.
TEST(DgramLink, QuantisedSlotsChainWithinADatagramOnly) {
  Session s;
  s.handshake(1, 0);
  size_t before = s.out.sent.size();
  const int64_t q = 250'000'000;
  const std::vector<ValueKind> kinds = {value_kind(ValueType::Float32, Aggregation::Max, 0.01)};
  const std::vector<uint32_t> ids = {0};
  auto value = [](uint64_t k) { return 20.0 + 0.03 * static_cast<double>(k); };
  for (uint64_t k = 0; k < 10; ++k) {
    Value v;
    v.present = true;
    v.number = value(k);
    Chain empty;
    std::vector<uint8_t> alone;
    encode_slot_values(alone, std::vector<Value>{v}, kinds, ids, empty);
    SlotEncoder enc = [v, kinds, ids](Chain& chain) {
      std::vector<uint8_t> out;
      encode_slot_values(out, std::vector<Value>{v}, kinds, ids, chain);
      return out;
    };
    s.link.add_slot(1, k, static_cast<int64_t>(k + 1) * q, std::move(alone), {true},
                    std::move(enc));
    s.link.tick(static_cast<int64_t>(k + 1) * q);
  }
  s.link.tick(20 * q);
  ASSERT_EQ(s.out.sent.size(), before + 2);  // slots 0..4 and 5..9
  for (size_t d = 0; d < 2; ++d) {
    auto v = dg::verify_data(s.out.sent[before + d], s.key, dg::kDroneToBase, 0);
    EXPECT_EQ(v.values.size(), 2u + 4 * 1) << "an absolute 2-byte value, then 1-byte deltas";
    ByteReader r(v.values);
    Chain chain;  // each datagram alone, as the receiver decodes it
    for (uint64_t k = v.slot; k < v.slot + 5; ++k)
      EXPECT_NEAR(decode_slot_value(r, kinds[0], chain, 0).number, value(k), 0.005) << k;
    r.expect_end();
  }
}
