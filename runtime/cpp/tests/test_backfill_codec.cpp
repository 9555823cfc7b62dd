// Backfill frames: the shared vectors contracts/vectors/link/backfill.json (written by
// the Python codec) decoded and re-encoded byte for byte by the C++ codec, and
// the invalid ones refused.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "modd/link/backfill.hpp"
#include "modd/util/bytes.hpp"

using namespace modd;
using namespace modd::link;
using nlohmann::json;
namespace bf = modd::link::backfill;

namespace {

json doc() {
  std::ifstream f(std::string(MODD_VECTORS_DIR) + "/backfill.json");
  EXPECT_TRUE(f.good());
  return json::parse(f);
}

ValueKind kind_of(const json& m) {
  ValueType t;
  Aggregation a;
  EXPECT_TRUE(parse_value_type(m["value_type"], t));
  EXPECT_TRUE(parse_aggregation(m["aggregation"], a));
  return value_kind(t, a);
}

bf::EndStatus status_of(const std::string& s) {
  const char* names[] = {"DONE", "CANCELLED", "UNKNOWN_TOPIC", "BAD_REQUEST", "BUSY", "IO"};
  for (uint8_t i = 0; i < 6; ++i)
    if (s == names[i]) return static_cast<bf::EndStatus>(i);
  throw std::runtime_error("status " + s);
}

bf::Message from_json(const json& m) {
  std::string t = m["type"];
  if (t == "BACKFILL_REQUEST") {
    bf::Request q;
    q.request_id = m["request_id"];
    q.topic = m["topic"];
    EXPECT_TRUE(parse_value_type(m["value_type"], q.type));
    EXPECT_TRUE(parse_aggregation(m["aggregation"], q.aggregation));
    q.period_us = m["period_us"];
    q.from_ns = m["from_ns"];
    q.windows = m["windows"];
    q.resume = m["resume"];
    q.rate_bps = m["rate_bps"];
    q.percentile = m.value("percentile", 0.0);
    if (m.contains("event")) {
      const json& e = m["event"];
      q.event.code = e["code"];
      q.event.deadband = e["deadband"];
      q.event.level = e["level"];
      q.event.hysteresis = e["hysteresis"];
      q.event.max_events = e["max_events"];
      q.state_from_ns = m["state_from_ns"];
    }
    return q;
  }
  if (t == "BACKFILL_PROGRESS")
    return bf::Progress{m["request_id"], m["next"], m["windows"], m["bytes_sent"], m["rate_bps"]};
  if (t == "BACKFILL_END")
    return bf::End{m["request_id"], status_of(m["status"]), m["next"], m["message"]};
  return bf::Cancel{m["request_id"]};
}

}  // namespace

TEST(BackfillCodec, VectorsByteForByte) {
  json v = doc();
  int n = 0;
  for (const auto& c : v["vectors"]) {
    SCOPED_TRACE(c["name"].get<std::string>());
    auto wire = from_hex(c["hex"].get<std::string>());
    auto f = split_frame(wire);
    ASSERT_TRUE(f);
    ASSERT_TRUE(bf::is_backfill_type(f->type));
    const json& m = c["message"];
    std::vector<uint8_t> out;
    if (m["type"] == "BACKFILL_DATA") {
      ValueKind k = kind_of(m);
      EXPECT_EQ(bf::data_request_id(*f), m["request_id"].get<uint64_t>());
      bf::DataFrame d = bf::decode_data(*f, k);
      EXPECT_EQ(d.first, m["first"].get<uint64_t>());
      ASSERT_EQ(d.values.size(), m["values"].size());
      for (size_t i = 0; i < d.values.size(); ++i) {
        const json& x = m["values"][i];
        EXPECT_EQ(d.values[i].present, x["present"].get<bool>());
        if (!d.values[i].present) continue;
        EXPECT_EQ(d.values[i].number, x["number"].get<double>());
        EXPECT_EQ(d.values[i].integer, x["integer"].get<int64_t>());
        EXPECT_EQ(d.values[i].count, x["count"].get<uint64_t>());
      }
      bf::encode_data(out, d, k);
    } else {
      bf::Message got = bf::decode(*f);
      EXPECT_TRUE(got == from_json(m));
      bf::encode(out, got);
    }
    EXPECT_EQ(to_hex(out), c["hex"].get<std::string>());
    ++n;
  }
  EXPECT_GE(n, 9);
}

TEST(BackfillCodec, InvalidFramesAreRejected) {
  json v = doc();
  for (const auto& c : v["invalid"]) {
    SCOPED_TRACE(c["name"].get<std::string>());
    auto wire = from_hex(c["hex"].get<std::string>());
    auto f = split_frame(wire);
    ASSERT_TRUE(f);
    if (f->type == static_cast<uint8_t>(bf::Type::Data))
      EXPECT_THROW(bf::decode_data(*f, value_kind(ValueType::Float32, Aggregation::Min)), Error);
    else
      EXPECT_THROW(bf::decode(*f), Error);
  }
}

TEST(BackfillCodec, WindowTimesAreTheOriginalOnes) {
  bf::Request q;
  q.from_ns = 1'000'000'000'000'000'000ull;
  q.period_us = 250'000;
  EXPECT_EQ(q.window_start_ns(3), 1'000'000'000'750'000'000ll);
}
