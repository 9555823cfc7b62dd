// Wall-clock steps against the broker's timeline (util/clock.hpp, docs/pubbroker.md "Clock
// steps"): a companion computer without RTC boots on a stale clock and GPS/NTP sets it
// (+3 days, +30 days), or NTP sets it back (-2 h). The schedule keeps its cadence across the
// step, walks no missed slot and holds none, and the archive keeps every sample.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "modd/archive/reader.hpp"
#include "modd/broker/broker.hpp"

using namespace modd;
using namespace modd::broker;
using namespace modd::link;

namespace {

constexpr int64_t kMs = 1'000'000;
constexpr int64_t kHour = 3'600'000 * kMs;

// A datagram link: every slot, empty ones included, is handed over (as over udp and serial).
struct SlotLink : LinkOutput {
  uint64_t slots = 0, bytes = 0;
  bool link_ready() const override { return true; }
  bool link_write(std::vector<uint8_t>&& b) override {
    bytes += b.size();
    return true;
  }
  bool datagrams() const override { return true; }
  bool link_slot(uint8_t, uint64_t, int64_t, std::vector<uint8_t>&& values, std::vector<bool>&&,
                 link::SlotEncoder&&) override {
    ++slots;
    bytes += values.size() + 1;
    return true;
  }
};

BrokerConfig step_config(const std::string& name) {
  BrokerConfig c;
  c.archive_dir =
      (std::filesystem::temp_directory_path() / ("modd-step-" + name + std::to_string(getpid())))
          .string();
  std::filesystem::remove_all(c.archive_dir);
  c.topics = {{"usv.x", ValueType::Float32, 4}};
  c.status_period_s = 0;
  c.max_future_ms = 10'000;  // publishers on the drone's clock: judged against it as it reads
  c.max_past_ms = 3'600'000;
  return c;
}

// One publisher on the broker's machine: a sample every 50 ms stamped by the wall clock.
struct Drone {
  FakeClock clock;
  SlotLink link;
  BrokerConfig cfg;
  Broker broker;
  IngressSession pub;
  uint64_t sent = 0;

  explicit Drone(const std::string& name)
      : cfg(step_config(name)), broker(cfg, "key", clock, link), pub(broker) {
    Config c;
    c.config_id = 1;
    c.topics = {{"usv.x", ValueType::Float32, 4, 40000}};
    c.streams = {{0, Aggregation::Max, 250000},
                 {0, Aggregation::Count, 500000}};  // hyperperiod 0.5 s
    EXPECT_EQ(broker.on_config(c).status, 0);
    std::vector<uint8_t> b;
    ingress::encode_hello(b, {ingress::kVersion, "p"});
    ingress::encode_register(b, {0, ValueType::Float32, "usv.x"});
    EXPECT_TRUE(pub.on_bytes(b));
  }
  ~Drone() { std::filesystem::remove_all(cfg.archive_dir); }

  // `ms` of elapsed time: a sample every 50 ms, the server's timer between them.
  void fly(int64_t ms) {
    for (int64_t t = 0; t < ms; t += 50) {
      clock.advance(50 * kMs);
      std::vector<uint8_t> b;
      ingress::encode_samples(b, std::vector<ingress::Record>{{0, clock.now_ns(), 1.0, 0}},
                              [](uint32_t) { return ValueType::Float32; });
      ASSERT_TRUE(pub.on_bytes(b));
      ++sent;
      broker.tick(broker.now());
    }
  }
};

nlohmann::json run_record(const std::string& dir) {
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().string().ends_with(".counters.json"))
      return nlohmann::json::parse(std::ifstream(e.path()));
  return {};
}

class ClockStep : public ::testing::TestWithParam<int64_t> {};

}  // namespace

TEST_P(ClockStep, CostsNothing) {
  const int64_t delta = GetParam();
  Drone d("p" + std::to_string(delta < 0 ? -delta / kMs : delta / kMs));
  d.fly(2000);
  const uint64_t slots_before = d.link.slots, bytes_before = d.link.bytes;
  ASSERT_EQ(slots_before, 8u);  // 4 slots a second (0.25 s and 0.5 s streams)
  d.clock.step(delta);
  d.fly(500);  // one hyperperiod after the step: live slots again
  EXPECT_GE(d.link.slots - slots_before, 2u);
  d.fly(1500);
  // The plan's cadence exactly: no missed slot walked (+30 d is 10.4 M slots), none held (-2 h).
  EXPECT_EQ(d.link.slots - slots_before, slots_before);
  EXPECT_LE(d.link.bytes - bytes_before, 2 * bytes_before);
  // What happened is said: one step, by delta, in the run's record.
  EXPECT_EQ(d.broker.timeline().steps(), 1u);
  d.broker.shutdown();
  EXPECT_EQ(d.broker.archiver().counters().archived.load(), d.sent);
  EXPECT_EQ(d.broker.counters().rej(broker::Reject::Timestamp), 0u);
  nlohmann::json rec = run_record(d.cfg.archive_dir);
  ASSERT_TRUE(rec.contains("clock")) << rec.dump();
  EXPECT_EQ(rec["clock"]["steps"], 1);
  EXPECT_EQ(rec["clock"]["last_step_ns"].get<int64_t>(), delta);
  EXPECT_EQ(rec["clock"]["wall_minus_timeline_ns"].get<int64_t>(), delta);
  // Every sample archived, log times on the timeline: 50 ms apart across the step.
  archive::TopicReader r(d.cfg.archive_dir, d.cfg.archive_prefix, "usv.x", ValueType::Float32);
  std::vector<int64_t> stamps;
  while (auto s = r.peek(0)) {
    stamps.push_back(s->stamp_ns);
    r.pop();
  }
  ASSERT_EQ(stamps.size(), d.sent);
  for (size_t i = 1; i < stamps.size(); ++i) EXPECT_EQ(stamps[i] - stamps[i - 1], 50 * kMs) << i;
}

INSTANTIATE_TEST_SUITE_P(Steps, ClockStep,
                         ::testing::Values(3 * 24 * kHour, 30 * 24 * kHour, -2 * kHour, 1000 * kMs),
                         [](const auto& info) {
                           int64_t d = info.param;
                           return std::string(d < 0 ? "back_" : "forward_") +
                                  std::to_string((d < 0 ? -d : d) / kMs) + "ms";
                         });

TEST(Timeline, SlewIsNoStepAndEveryStepIsCounted) {
  FakeClock c;
  Timeline t(c);
  const int64_t t0 = t.now();
  EXPECT_EQ(t0, c.now_ns());
  for (int i = 0; i < 100; ++i) {  // NTP slewing at its limit, 0.5 ms/s
    c.advance(1'000 * kMs);
    c.step(kMs / 2);
    t.now();
  }
  EXPECT_EQ(t.steps(), 0u);
  EXPECT_EQ(t.offset_ns(), 50 * kMs);
  c.step(-2 * kHour);
  int64_t at = t.now();
  EXPECT_EQ(at, t0 + 100'000 * kMs);  // elapsed time only
  EXPECT_EQ(t.steps(), 1u);
  EXPECT_EQ(t.last_step().delta_ns, -2 * kHour);
  EXPECT_EQ(t.wall(), c.now_ns());
  t.now();
  EXPECT_EQ(t.last_step().delta_ns, 0);  // said once
}
