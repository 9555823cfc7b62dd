// The shared vectors in contracts/vectors/link/: the C++ codec decodes each hex to the
// listed message and encodes the message back to the same bytes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "modd/link/auth.hpp"
#include "modd/link/codec.hpp"
#include "modd/link/schedule.hpp"
#include "modd/util/bytes.hpp"

using namespace modd;
using namespace modd::link;
using nlohmann::json;

namespace {

json load(const std::string& name) {
  std::ifstream f(std::string(MODD_VECTORS_DIR) + "/" + name);
  EXPECT_TRUE(f.good()) << name;
  return json::parse(f);
}

template <size_t N>
std::array<uint8_t, N> arr(const std::string& hex) {
  auto v = from_hex(hex);
  std::array<uint8_t, N> a{};
  EXPECT_EQ(v.size(), N);
  std::copy_n(v.begin(), std::min(N, v.size()), a.begin());
  return a;
}

Message from_json(const json& m) {
  std::string t = m["type"];
  if (t == "HELLO") return Hello{m["version"].get<uint8_t>(), arr<16>(m["nonce"])};
  if (t == "CHALLENGE") return Challenge{m["version"].get<uint8_t>(), arr<16>(m["nonce"])};
  if (t == "AUTH") return Auth{arr<32>(m["mac"])};
  if (t == "AUTH_OK")
    return AuthOk{arr<32>(m["mac"]), m["config_id"].get<uint8_t>(), m["epoch_ns"].get<uint64_t>()};
  if (t == "PING") return Ping{from_hex(m["payload"].get<std::string>())};
  if (t == "PONG") return Pong{from_hex(m["payload"].get<std::string>())};
  if (t == "CONFIG_ACK") return ConfigAck{m["config_id"], m["status"], m["epoch_ns"]};
  if (t == "ONBOARD")
    return Onboard{m["config_id"].get<uint8_t>(), from_hex(m["model"].get<std::string>())};
  if (t == "ONBOARD_ACK")
    return OnboardAck{m["config_id"].get<uint8_t>(), m["status"].get<uint8_t>(),
                      from_hex(m["answers"].get<std::string>())};
  if (t == "STATUS") {
    Status s{m["counters"].get<std::vector<uint64_t>>()};
    for (const auto& h : m.value("sensors", json::array()))
      s.sensors.push_back({h["name"], h["fields"].get<std::vector<uint64_t>>()});
    return s;
  }
  if (t == "ERROR") return ErrorMsg{m["code"], m["message"]};
  if (t == "CONFIG") {
    Config c;
    c.config_id = m["config_id"];
    c.status_period_s = m["status_period_s"];
    for (const auto& tj : m["topics"]) {
      TopicSpec ts;
      ts.name = tj["name"];
      EXPECT_TRUE(parse_value_type(tj["type"], ts.type));
      ts.buffer_size = tj["buffer_size"];
      ts.period_us = tj["period_us"];
      c.topics.push_back(ts);
    }
    for (const auto& sj : m["streams"]) {
      StreamSpec s;
      s.topic = sj["topic"];
      EXPECT_TRUE(parse_aggregation(sj["aggregation"], s.aggregation));
      s.period_us = sj["period_us"];
      s.percentile = sj.value("percentile", 0.0);
      if (sj.contains("event")) {
        const json& e = sj["event"];
        s.event.code = e["code"];
        s.event.deadband = e["deadband"];
        s.event.level = e["level"];
        s.event.hysteresis = e["hysteresis"];
        s.event.max_events = e["max_events"];
      }
      c.streams.push_back(s);
    }
    if (m.contains("accepted_delay_ms"))
      c.accepted_delay_ms = m["accepted_delay_ms"].get<uint32_t>();
    if (m.contains("resolutions"))
      for (const auto& x : m["resolutions"])
        c.resolutions.push_back(x.is_null() ? 0.0 : x.get<double>());
    return c;
  }
  ADD_FAILURE() << "unknown vector type " << t;
  return Ping{};
}

// A vector's value kind: type, aggregation and the optional declared resolution.
ValueKind kind_of(const json& k) {
  ValueType t{};
  Aggregation a{};
  EXPECT_TRUE(parse_value_type(k["type"], t)) << k;
  EXPECT_TRUE(parse_aggregation(k["aggregation"], a)) << k;
  return value_kind(t, a, k.value("resolution", 0.0));
}

bool same(const Message& a, const Message& b) {
  std::vector<uint8_t> x, y;
  encode(x, a);
  encode(y, b);
  return x == y && a.index() == b.index();
}

}  // namespace

TEST(Vectors, EveryMessageVectorDecodesAndEncodesByteForByte) {
  int n = 0;
  for (const auto& entry : std::filesystem::directory_iterator(MODD_VECTORS_DIR)) {
    std::string name = entry.path().filename();
    if (entry.path().extension() != ".json") continue;
    json v = load(name);
    if (!v.contains("message") || v["message"]["type"] == "DATA") continue;
    SCOPED_TRACE(name);
    auto wire = from_hex(v["hex"].get<std::string>());
    auto f = split_frame(wire);
    ASSERT_TRUE(f);
    EXPECT_EQ(f->size, wire.size());
    Message decoded = decode(*f);
    Message expected = from_json(v["message"]);
    EXPECT_TRUE(same(decoded, expected));
    std::vector<uint8_t> out;
    encode(out, expected);
    EXPECT_EQ(to_hex(out), v["hex"].get<std::string>());
    if (auto* c = std::get_if<Config>(&decoded)) { EXPECT_EQ(*c, std::get<Config>(expected)); }
    ++n;
  }
  EXPECT_GE(n, 12);
}

TEST(Vectors, DataVectors) {
  int n = 0;
  for (const auto& entry : std::filesystem::directory_iterator(MODD_VECTORS_DIR)) {
    std::string name = entry.path().filename();
    if (entry.path().extension() != ".json") continue;
    json v = load(name);
    if (!v.contains("message") || v["message"]["type"] != "DATA") continue;
    SCOPED_TRACE(name);
    std::vector<ValueKind> kinds;
    for (const auto& k : v["kinds"]) kinds.push_back(kind_of(k));
    const json& m = v["message"];
    Data d;
    d.sync = m["sync"];
    d.config_id = m["config_id"];
    d.slot = m["slot"];
    d.seq8 = m["seq8"];
    for (const auto& vj : m["values"]) {
      Value x;
      x.present = vj["present"];
      x.number = vj["number"];
      x.integer = vj["integer"];
      x.count = vj["count"];
      bool int_kind = kinds[d.values.size()].scalar == ScalarKind::ZigZag ||
                      kinds[d.values.size()].scalar == ScalarKind::Bool;
      for (const auto& s : vj["samples"]) {
        if (s.is_number_integer() && (int_kind || !is_event(kinds[d.values.size()].aggregation)))
          x.integers.push_back(s.get<int64_t>());
        else
          x.numbers.push_back(s.get<double>());
      }
      if (vj.contains("times_us")) {
        x.times_us = vj["times_us"].get<std::vector<uint64_t>>();
        x.coalesced = vj["coalesced"];
      }
      d.values.push_back(x);
    }
    std::vector<uint8_t> out;
    encode_data(out, d, kinds);
    EXPECT_EQ(to_hex(out), v["hex"].get<std::string>());
    auto wire = from_hex(v["hex"].get<std::string>());
    auto f = split_frame(wire);
    ASSERT_TRUE(f);
    Data back = decode_data(*f, kinds);
    EXPECT_EQ(back.sync, d.sync);
    if (d.sync) {
      EXPECT_EQ(back.config_id, d.config_id);
      EXPECT_EQ(back.slot, d.slot);
    }
    EXPECT_EQ(back.seq8, d.seq8);
    ASSERT_EQ(back.values.size(), d.values.size());
    for (size_t i = 0; i < d.values.size(); ++i) {
      EXPECT_EQ(back.values[i].present, d.values[i].present) << i;
      if (!d.values[i].present) continue;
      EXPECT_EQ(back.values[i].number, d.values[i].number) << i;
      EXPECT_EQ(back.values[i].integer, d.values[i].integer) << i;
      EXPECT_EQ(back.values[i].count, d.values[i].count) << i;
      EXPECT_EQ(back.values[i].integers, d.values[i].integers) << i;
      if (is_event(kinds[i].aggregation)) {
        EXPECT_EQ(back.values[i].numbers, d.values[i].numbers) << i;
      }
      EXPECT_EQ(back.values[i].times_us, d.values[i].times_us) << i;
      EXPECT_EQ(back.values[i].coalesced, d.values[i].coalesced) << i;
    }
    ++n;
  }
  EXPECT_GE(n, 5);
}

TEST(Vectors, InvalidFramesAreRejected) {
  json v = load("invalid.json");
  for (const auto& f : v["frames"]) {
    SCOPED_TRACE(f["name"].get<std::string>());
    auto wire = from_hex(f["hex"].get<std::string>());
    EXPECT_THROW(
        {
          auto raw = split_frame(wire);
          if (!raw) throw Error(ErrorCode::BadFrame, "incomplete");
          (void)decode(*raw);
        },
        Error);
  }
}

TEST(Vectors, HandshakeProofs) {
  json v = load("handshake.json");
  auto key = from_hex(v["key"].get<std::string>());
  auto cn = arr<16>(v["client_nonce"]);
  auto sn = arr<16>(v["server_nonce"]);
  EXPECT_EQ(to_hex(client_proof(key, cn, sn)), v["client_proof"].get<std::string>());
  EXPECT_EQ(to_hex(server_proof(key, cn, sn)), v["server_proof"].get<std::string>());
  // the keyed HELLO nonce the SubBroker makes (docs/protocol.md, "Keyed HELLO")
  auto random = arr<8>(v["keyed_random"]);
  Nonce keyed = keyed_nonce(key, random);
  EXPECT_EQ(to_hex(keyed), v["keyed_nonce"].get<std::string>());
  EXPECT_TRUE(is_keyed_nonce(key, keyed));
  EXPECT_FALSE(is_keyed_nonce(key, cn));
}

TEST(Vectors, SlotTable) {
  json v = load("slots.json");
  auto periods = v["periods_us"].get<std::vector<uint64_t>>();
  SlotIterator it(periods);
  for (const auto& s : v["slots"]) {
    Slot got = it.next();
    EXPECT_EQ(got.index, s["index"].get<uint64_t>());
    EXPECT_EQ(got.offset_us, s["offset_us"].get<uint64_t>());
    EXPECT_EQ(got.streams, s["streams"].get<std::vector<uint32_t>>());
  }
}

// Declared resolution (contracts/vectors/link/quantised.json): each unit is the values of the
// slots of one DATA datagram, one chain of steps per stream starting empty.
TEST(Vectors, QuantisedUnitsDecodeAndEncodeByteForByte) {
  json v = load("quantised.json");
  ASSERT_GE(v["units"].size(), 3u);
  for (const auto& u : v["units"]) {
    SCOPED_TRACE(u["name"].get<std::string>());
    std::vector<ValueKind> kinds;
    for (const auto& k : u["kinds"]) kinds.push_back(kind_of(k));
    auto wire = from_hex(u["hex"].get<std::string>());
    ByteReader r(wire);
    Chain chain, again_chain;
    std::vector<uint8_t> again;
    for (const auto& slot : u["slots"]) {
      std::vector<Value> values;
      std::vector<ValueKind> slot_kinds;
      std::vector<uint32_t> ids;
      for (size_t i = 0; i < slot["streams"].size(); ++i) {
        uint32_t s = slot["streams"][i];
        const json& want = slot["values"][i];
        Value x;
        x.present = want["present"];
        if (x.present) {
          Value got = decode_slot_value(r, kinds[s], chain, s);
          if (kinds[s].aggregation == Aggregation::All) {
            EXPECT_EQ(got.numbers, want["samples"].get<std::vector<double>>());
          } else {
            EXPECT_EQ(got.number, want["number"].get<double>());
          }
          EXPECT_EQ(got.count, want["count"].get<uint64_t>());
          x = got;
        }
        values.push_back(x);
        slot_kinds.push_back(kinds[s]);
        ids.push_back(s);
      }
      encode_slot_values(again, values, slot_kinds, ids, again_chain);
    }
    r.expect_end();
    EXPECT_EQ(to_hex(again), u["hex"].get<std::string>());
  }
}

TEST(Vectors, QuantisedStepsMatchThePythonRounding) {
  EXPECT_EQ(*quantise_steps(0.125, 0.25), 0);  // ties to even, as Python's round()
  EXPECT_EQ(*quantise_steps(0.375, 0.25), 2);
  EXPECT_EQ(*quantise_steps(-700.25, 0.5), -1400);  // -1400.5 steps, to even
  EXPECT_FALSE(quantise_steps(1e300, 0.01));
  EXPECT_FALSE(quantise_steps(std::numeric_limits<double>::quiet_NaN(), 0.01));
  std::vector<uint8_t> big;
  ByteWriter w(big);
  w.varint((uint64_t{1} << 55) + 1);  // a delta of -2^54 - 1 steps
  ByteReader r(big);
  Chain c;
  EXPECT_THROW(get_number(r, c, 0, 1.0), Error);
}
