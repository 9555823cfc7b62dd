// Instruments' health at the ingress and in STATUS (docs/protocol.md, "Instruments' health"):
// names made printable, numbers in range, a STATUS that fits its room with every instrument
// counted, and state changes within the change budget (one STATUS of their own a period).
#include <gtest/gtest.h>

#include <filesystem>

#include "modd/broker/broker.hpp"
#include "modd/broker/dgram_link.hpp"
#include "modd/broker/health.hpp"
#include "modd/link/codec.hpp"

using namespace modd;
using namespace modd::broker;
using namespace modd::link;

namespace {

struct FakeLink : LinkOutput {
  std::vector<std::vector<uint8_t>> writes;
  bool link_ready() const override { return true; }
  bool link_write(std::vector<uint8_t>&& b) override {
    writes.push_back(std::move(b));
    return true;
  }
  Status status(size_t i) const { return std::get<Status>(decode(*split_frame(writes.at(i)))); }
};

BrokerConfig health_config(const std::string& name) {
  BrokerConfig c;
  c.archive_dir =
      (std::filesystem::temp_directory_path() / ("modd-health-" + name + std::to_string(getpid())))
          .string();
  std::filesystem::remove_all(c.archive_dir);
  c.topics = {{"usv.x", ValueType::Float32, 4}};
  c.status_period_s = 1;
  c.max_future_ms = 0;
  c.max_past_ms = 0;
  return c;
}

std::vector<uint8_t> health_bytes(const std::vector<SensorHealth>& sensors) {
  std::vector<uint8_t> b;
  ingress::encode_hello(b, {ingress::kVersion, "sensors"});
  ingress::encode_health(b, sensors);
  return b;
}

// `n` instruments of the longest name and the most fields, at the largest counts.
std::vector<SensorHealth> big_instruments(size_t n, char tag, uint64_t state) {
  std::vector<SensorHealth> out;
  for (size_t i = 0; i < n; ++i) {
    std::string name(kMaxHealthName, tag);
    name.replace(0, 3, std::to_string(100 + i));
    SensorHealth h{name, std::vector<uint64_t>(kMaxHealthFields, kMaxHealthCount)};
    h.fields[0] = state;
    h.fields[4] = kMaxLastValueMs;
    out.push_back(h);
  }
  return out;
}

constexpr int64_t kMs = 1'000'000;
constexpr uint64_t k2p53 = uint64_t{1} << 53, k2p63 = uint64_t{1} << 63;

}  // namespace

TEST(Health, NamesAreMadePrintable) {
  EXPECT_EQ(printable_name("gnss-1 µ°C"), "gnss-1 µ°C");            // UTF-8 kept
  EXPECT_EQ(printable_name("\x1b[31mred\x1b[0m"), "?[31mred?[0m");  // no ANSI escape
  EXPECT_EQ(printable_name("a\xff\xfe"
                           "b"),
            "a??b");                                          // not UTF-8
  EXPECT_EQ(printable_name("\xc0\xaf"), "??");                // overlong '/'
  EXPECT_EQ(printable_name("\xed\xa0\x80"), "???");           // a surrogate
  EXPECT_EQ(printable_name("x\xc2\x85y\r\n\x7f"), "x?y???");  // C1 NEL, CR LF, DEL
  EXPECT_EQ(printable_name("\xe2\x80\xaegps"), "?gps");       // a bidi override
  EXPECT_EQ(printable_name("\xe2\x82"), "??");                // a cut sequence
}

TEST(Health, NumbersAreBroughtIntoRange) {
  SensorHealth h{"ctd", {7, k2p63, 3, k2p53, k2p53, 5, UINT64_MAX}};
  EXPECT_EQ(sanitise_health(h), 5u);
  std::vector<uint64_t> want = {kStateSilent,   kMaxHealthCount, 3, kMaxHealthCount, 0, 5,
                                kMaxHealthCount};
  EXPECT_EQ(h.fields, want);
  SensorHealth fine{"gnss", {1, 10, 0, 0, 1'764'892'800'000, 9}};
  SensorHealth copy = fine;
  EXPECT_EQ(sanitise_health(copy), 0u);
  EXPECT_EQ(copy, fine);
}

TEST(Health, AStatusWithEveryInstrumentFitsItsRoomAndCountsTheRest) {
  for (size_t room : {control_frame_room(248), control_frame_room(1472), kStatusRoomTcp}) {
    auto all = big_instruments(100, 'o', kStateOpen);
    auto silent = big_instruments(3, 's', kStateSilent);
    all.insert(all.end(), silent.begin(), silent.end());
    Status st = fit_status(std::vector<uint64_t>(kStatusFieldCount, 1'000'000), all, room);
    std::vector<uint8_t> frame;
    encode(frame, st);
    EXPECT_LE(frame.size(), room);
    const auto& c = st.counters;
    EXPECT_EQ(c[at(StatusField::Instruments)], 103u);
    EXPECT_EQ(c[at(StatusField::InstrumentsOpen)], 100u);
    EXPECT_EQ(c[at(StatusField::InstrumentsSilent)], 3u);
    EXPECT_EQ(c[at(StatusField::InstrumentsUnlisted)], 103u - st.sensors.size());
    if (room >= 1000) {  // the silent ones are listed before any open one
      ASSERT_GE(st.sensors.size(), 4u);
      size_t listed_silent = 0;
      for (const auto& s : st.sensors) listed_silent += s.fields[0] == kStateSilent;
      EXPECT_EQ(listed_silent, 3u);
    }
    Status back = std::get<Status>(decode(*split_frame(frame)));  // a reader takes it whole
    EXPECT_EQ(back.sensors, st.sensors);
  }
}

TEST(Health, AForgedNameAndAHugeNumberNeverReachStatus) {
  FakeClock clock;
  FakeLink link;
  Broker b(health_config("forged"), "key", clock, link);
  IngressSession s(b);
  ASSERT_TRUE(s.on_bytes(health_bytes({{"\xff\xfe\x1b[2Jgps", {1, 1, 0, 0, k2p63}}})));
  ASSERT_EQ(link.writes.size(), 1u);  // a new instrument: a STATUS at once
  Status st = link.status(0);
  ASSERT_EQ(st.sensors.size(), 1u);
  EXPECT_EQ(st.sensors[0].name, "???[2Jgps");
  EXPECT_EQ(st.sensors[0].fields[4], 0u);  // beyond 2100: "none"
  EXPECT_EQ(st.counters[at(StatusField::HealthCorrected)], 2u);
}

TEST(Health, FlappingInstrumentsCostOneStatusAPeriod) {
  FakeClock clock;
  FakeLink link;
  Broker b(health_config("flap"), "key", clock, link);
  IngressSession s(b);
  // 64 instruments flipping 20 times a second for 3 s: 60 changes.
  for (int i = 0; i < 60; ++i) {
    ASSERT_TRUE(s.on_bytes(health_bytes(big_instruments(64, 'f', i % 2 ? kStateOpen : 2))));
    clock.advance(50 * kMs);
    b.send_overdue_status(b.now());
  }
  // One at once, then at most one a period (1 s): 3 in 3 s, each within its room.
  EXPECT_LE(link.writes.size(), 4u);
  EXPECT_GE(link.writes.size(), 3u);
  for (const auto& w : link.writes) EXPECT_LE(w.size(), kStatusRoomTcp);
  EXPECT_GE(link.status(link.writes.size() - 1).counters[at(StatusField::StatusCoalesced)], 50u);
  EXPECT_EQ(link.status(0).counters[at(StatusField::Instruments)], 64u);
  // The last change is not lost: it goes at the end of the period.
  size_t before = link.writes.size();
  ASSERT_TRUE(s.on_bytes(health_bytes(big_instruments(64, 'f', kStateClosed))));
  clock.advance(1000 * kMs);
  b.send_overdue_status(b.now());
  ASSERT_EQ(link.writes.size(), before + 1);
  EXPECT_EQ(link.status(before).counters[at(StatusField::InstrumentsClosed)], 64u);
}

TEST(Health, AClosedConnectionsHealthLeavesStatusWithinAPeriod) {
  FakeClock clock;
  FakeLink link;
  Broker b(health_config("closed"), "key", clock, link);
  auto s = std::make_unique<IngressSession>(b);
  ASSERT_TRUE(s->on_bytes(health_bytes({{"ctd", {1, 5}}})));
  ASSERT_EQ(link.writes.size(), 1u);
  s.reset();  // the publisher's connection closed
  clock.advance(1000 * kMs);
  b.send_overdue_status(b.now());
  ASSERT_EQ(link.writes.size(), 2u);
  EXPECT_TRUE(link.status(1).sensors.empty());
  EXPECT_EQ(link.status(1).counters[at(StatusField::Instruments)], 0u);
}

TEST(Health, AChangeIsToldWithinTenSecondsHoweverLongThePeriod) {
  FakeClock clock;
  FakeLink link;
  BrokerConfig cfg = health_config("gap");
  cfg.status_period_s = 60;
  Broker b(cfg, "key", clock, link);
  IngressSession s(b);
  ASSERT_TRUE(s.on_bytes(health_bytes({{"ctd", {1, 5}}})));
  ASSERT_EQ(link.writes.size(), 1u);  // new: at once
  ASSERT_TRUE(s.on_bytes(health_bytes({{"ctd", {0, 5}}})));
  EXPECT_EQ(b.status_wake_ns(), b.now() + int64_t{kMaxChangeGapS} * 1'000'000'000);
  clock.advance(9'000 * kMs);
  b.send_overdue_status(b.now());
  EXPECT_EQ(link.writes.size(), 1u);  // held: within the gap
  clock.advance(1'000 * kMs);
  b.send_overdue_status(b.now());
  ASSERT_EQ(link.writes.size(), 2u);  // 10 s after the first, not 60
  EXPECT_EQ(link.status(1).sensors.at(0).fields[0], kStateClosed);
}
