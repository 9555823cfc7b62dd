#include <gtest/gtest.h>

#include "modd/broker/executor.hpp"
#include "modd/link/codec.hpp"
#include "modd/util/clock.hpp"

using namespace modd;
using namespace modd::broker;
using namespace modd::link;

namespace {

struct CaptureSink : FrameSink {
  bool up = true;
  std::vector<std::vector<uint8_t>> frames;
  bool send_data(std::vector<uint8_t>&& f) override {
    if (!up) return false;
    frames.push_back(std::move(f));
    return true;
  }
};

Config scenario1(uint8_t id) {
  Config c;
  c.config_id = id;
  for (const char* n : {"x", "y", "z"}) c.topics.push_back({n, ValueType::Float32, 28, 40000});
  c.streams = {{0, Aggregation::Average, 250000},
               {1, Aggregation::Average, 250000},
               {2, Aggregation::Min, 250000},
               {2, Aggregation::Max, 250000}};
  return c;
}

std::vector<ValueKind> kinds(const Config& c, const std::vector<uint32_t>& ids) {
  std::vector<ValueKind> k;
  for (uint32_t i : ids)
    k.push_back(value_kind(c.topics[c.streams[i].topic].type, c.streams[i].aggregation));
  return k;
}

constexpr int64_t kMs = 1'000'000;
const std::vector<uint32_t> kGlobals = {0, 1, 2};

}  // namespace

TEST(Executor, OneFramePerSlotWithTheWindowAggregates) {
  FakeClock clock;
  int64_t E = clock.now_ns();
  Executor ex;
  CaptureSink sink;
  Config c = scenario1(1);
  EXPECT_EQ(ex.apply(c, kGlobals, E), E);
  EXPECT_EQ(ex.next_due_ns(), E + 250 * kMs);
  ex.on_sample(0, 1.0, 0);
  ex.on_sample(0, 2.0, 0);
  ex.on_sample(2, -3.0, 0);
  ex.on_sample(2, 5.0, 0);
  ex.advance(E + 249 * kMs, sink);
  EXPECT_TRUE(sink.frames.empty());
  ex.advance(E + 250 * kMs, sink);  // the due date itself fires the slot
  ASSERT_EQ(sink.frames.size(), 1u);
  auto f = split_frame(sink.frames[0]);
  Data d = decode_data(*f, kinds(c, {0, 1, 2, 3}));
  EXPECT_TRUE(d.sync);  // first frame of a config
  EXPECT_EQ(d.config_id, 1);
  EXPECT_EQ(d.slot, 0u);
  EXPECT_DOUBLE_EQ(d.values[0].number, 1.5);
  EXPECT_EQ(d.values[0].count, 2u);
  EXPECT_FALSE(d.values[1].present);  // no y sample: absent, not resent
  EXPECT_EQ(d.values[2].number, -3.0);
  EXPECT_EQ(d.values[3].number, 5.0);
  // Next window: a sample after the boundary, then a late timer fires two slots at once.
  ex.on_sample(1, 4.0, 0);
  ex.advance(E + 760 * kMs, sink);
  ASSERT_EQ(sink.frames.size(), 2u);  // slot 1 has y; slot 2 is empty: nothing sent
  Data d1 = decode_data(*split_frame(sink.frames[1]), kinds(c, {0, 1, 2, 3}));
  EXPECT_FALSE(d1.sync);
  EXPECT_EQ(d1.seq8, 1);
  EXPECT_EQ(d1.values[1].number, 4.0);
  EXPECT_EQ(ex.counters().slots_empty, 1u);
  // After the empty slot, the next frame is a sync frame saying where it is.
  ex.on_sample(0, 1.0, 0);
  ex.advance(E + 1000 * kMs, sink);
  Data d3 = decode_data(*split_frame(sink.frames[2]), kinds(c, {0, 1, 2, 3}));
  EXPECT_TRUE(d3.sync);
  EXPECT_EQ(d3.slot, 3u);
}

TEST(Executor, DroppedFramesAreCountedAndFollowedBySync) {
  FakeClock clock;
  int64_t E = clock.now_ns();
  Executor ex;
  CaptureSink sink;
  Config c = scenario1(2);
  ex.apply(c, kGlobals, E);
  sink.up = false;
  ex.on_sample(0, 1.0, 0);
  ex.advance(E + 250 * kMs, sink);
  EXPECT_EQ(ex.counters().frames_dropped, 1u);
  sink.up = true;
  ex.on_sample(0, 1.0, 0);
  ex.advance(E + 500 * kMs, sink);
  Data d = decode_data(*split_frame(sink.frames[0]), kinds(c, {0, 1, 2, 3}));
  EXPECT_TRUE(d.sync);
  EXPECT_EQ(d.slot, 1u);
}

TEST(Executor, NewConfigSwitchesAtTheNextSlotWithoutLosingSamples) {
  FakeClock clock;
  int64_t E = clock.now_ns();
  Executor ex;
  CaptureSink sink;
  Config c1 = scenario1(1);
  ex.apply(c1, kGlobals, E);
  Config c2;
  c2.config_id = 2;
  c2.topics = c1.topics;
  c2.streams = {{0, Aggregation::Count, 100000}};
  ex.on_sample(0, 1.0, 0);
  auto epoch2 = ex.apply(c2, kGlobals, E + 100 * kMs);
  ASSERT_TRUE(epoch2);
  EXPECT_EQ(*epoch2, E + 250 * kMs);                    // at the running config's next slot
  EXPECT_FALSE(ex.apply(c2, kGlobals, E + 120 * kMs));  // one at a time: BUSY
  ex.on_sample(0, 3.0, 0);                              // still the old config's window
  ex.advance(E + 250 * kMs, sink);                      // old slot fires, then the switch
  EXPECT_EQ(ex.config_id(), 2);
  EXPECT_EQ(ex.epoch_ns(), E + 250 * kMs);
  ex.on_sample(0, 9.0, 0);
  ex.on_sample(0, 9.0, 0);
  ex.advance(E + 350 * kMs, sink);
  ASSERT_EQ(sink.frames.size(), 2u);
  Data old = decode_data(*split_frame(sink.frames[0]), kinds(c1, {0, 1, 2, 3}));
  EXPECT_EQ(old.values[0].count, 2u);
  EXPECT_DOUBLE_EQ(old.values[0].number, 2.0);
  Data nw = decode_data(*split_frame(sink.frames[1]), kinds(c2, {0}));
  EXPECT_TRUE(nw.sync);
  EXPECT_EQ(nw.config_id, 2);
  EXPECT_EQ(nw.slot, 0u);
  EXPECT_EQ(nw.values[0].count, 2u);  // exactly the samples after the switch
}

TEST(Executor, EventStreamsSendEachEventWithItsTimeInTheWindow) {
  FakeClock clock;
  int64_t E = clock.now_ns();
  Executor ex;
  CaptureSink sink;
  Config c;
  c.config_id = 3;
  c.topics.push_back({"x", ValueType::Float32, 28, 40000});
  c.topics.push_back({"n", ValueType::Int, 28, 40000});
  StreamSpec threshold{0, Aggregation::Threshold, 250000};
  threshold.event = {static_cast<uint8_t>(events::Crossing::Both), 0, 5.0, 0.5, 2};
  StreamSpec change{1, Aggregation::OnChange, 250000};
  change.event = {static_cast<uint8_t>(events::DeadbandMode::Absolute), 1.0, 0, 0, 0};
  c.streams = {threshold, change};
  ASSERT_EQ(ex.apply(c, {0, 1}, E), E);
  // x: below, then UP at 10 ms, DOWN at 20 ms, UP at 30 ms: N = 2 keeps the first and
  // the newest; n: 7 (an event), 7, 9 (an event: more than 1 away)
  double xs[] = {4.0, 6.0, 4.0, 6.0};
  for (int k = 0; k < 4; ++k) ex.on_sample(0, xs[k], 0, E + k * 10 * kMs + 1234);
  ex.on_sample(1, 0, 7, E + 5 * kMs);
  ex.on_sample(1, 0, 7, E + 6 * kMs);
  ex.on_sample(1, 0, 9, E + 7 * kMs);
  ex.advance(E + 250 * kMs, sink);
  ASSERT_EQ(sink.frames.size(), 1u);
  Data d = decode_data(*split_frame(sink.frames[0]), kinds(c, {0, 1}));
  EXPECT_EQ(d.values[0].numbers, (std::vector<double>{6.0, 6.0}));
  EXPECT_EQ(d.values[0].times_us, (std::vector<uint64_t>{10001, 30001}));  // µs, floored
  EXPECT_EQ(d.values[0].coalesced, 1u);
  EXPECT_EQ(d.values[1].integers, (std::vector<int64_t>{7, 9}));
  EXPECT_EQ(d.values[1].times_us, (std::vector<uint64_t>{5000, 7000}));
  EXPECT_EQ(ex.counters().events_coalesced, 1u);
  // the state carries over: x stays above (no event), n stays within 1 of 9: absent
  ex.on_sample(0, 5.2, 0, E + 300 * kMs);
  ex.on_sample(1, 0, 10, E + 310 * kMs);
  ex.advance(E + 500 * kMs, sink);
  EXPECT_EQ(sink.frames.size(), 1u);  // nothing to send
}
