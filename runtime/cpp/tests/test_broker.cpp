// The broker's logic driven without sockets: ingest validation and counting,
// CONFIG, DATA through the link output, and the archive at shutdown.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <thread>

#include "modd/broker/broker.hpp"
#include "modd/link/codec.hpp"

using namespace modd;
using namespace modd::broker;
using namespace modd::link;

namespace {

struct FakeLink : LinkOutput {
  bool ready = true;
  std::vector<std::vector<uint8_t>> writes;
  bool link_ready() const override { return ready; }
  bool link_write(std::vector<uint8_t>&& b) override {
    writes.push_back(std::move(b));
    return true;
  }
};

// Archive directories of the tests, removed when the test binary exits.
struct TempDirs {
  std::vector<std::string> dirs;
  ~TempDirs() {
    for (const auto& d : dirs) std::filesystem::remove_all(d);
  }
} temp_dirs;

BrokerConfig test_config(const std::string& name) {
  BrokerConfig c;
  c.archive_dir =
      (std::filesystem::temp_directory_path() / ("modd-broker-" + name + std::to_string(getpid())))
          .string();
  std::filesystem::remove_all(c.archive_dir);
  temp_dirs.dirs.push_back(c.archive_dir);
  c.topics = {{"usv.x", ValueType::Float32, 4}, {"usv.n", ValueType::Int, 0}};
  c.default_buffer_size = 3;
  c.status_period_s = 0;
  c.max_future_ms = 0;  // these tests stamp samples with small numbers: no timestamp bounds
  c.max_past_ms = 0;
  return c;
}

std::vector<uint8_t> publisher_bytes(const std::vector<ingress::Register>& regs,
                                     const std::vector<ingress::Record>& recs) {
  std::vector<uint8_t> b;
  ingress::encode_hello(b, {ingress::kVersion, "p"});
  for (const auto& r : regs) ingress::encode_register(b, r);
  ingress::encode_samples(b, recs, [&](uint32_t id) {
    for (const auto& r : regs)
      if (r.local_id == id) return r.type;
    return ValueType::Float32;
  });
  return b;
}

constexpr int64_t kMs = 1'000'000;

// One topic, one LAST stream, a STATUS a second.
Config status_config(uint8_t id) {
  Config c;
  c.config_id = id;
  c.status_period_s = 1;
  c.topics = {{"usv.x", ValueType::Float32, 2, 0}};
  c.streams = {{0, Aggregation::Last, 250000}};
  return c;
}

}  // namespace

TEST(Broker, RejectionsAreCountedByReason) {
  FakeClock clock;
  FakeLink link;
  BrokerConfig cfg = test_config("rej");
  Broker b(cfg, "key", clock, link);
  IngressSession s(b);
  std::vector<ingress::Register> regs = {{0, ValueType::Float32, "usv.x"},
                                         {1, ValueType::Float32, "usv.unknown"},
                                         {2, ValueType::Float64, "usv.n"}};
  std::vector<ingress::Record> recs = {
      {0, 100, 1.0, 0}, {0, 200, NAN, 0}, {0, 50, 2.0, 0},  // out of order: accepted
      {1, 300, 1.0, 0}, {2, 300, 1.0, 0}, {0, 200, INFINITY, 0}, {0, 200, 3.0, 0}};
  ASSERT_TRUE(s.on_bytes(publisher_bytes(regs, recs)));
  Counters& c = b.counters();
  EXPECT_EQ(c.samples_in, 7u);
  EXPECT_EQ(c.accepted, 3u);
  EXPECT_EQ(c.rej(Reject::NotFinite), 2u);
  EXPECT_EQ(c.rej(Reject::Timestamp), 0u);
  EXPECT_EQ(c.rej(Reject::UnknownTopic), 1u);
  EXPECT_EQ(c.rej(Reject::WrongType), 1u);
  // A malformed frame: counted, the session ends, nothing already accepted is lost.
  std::vector<uint8_t> junk;  // record 2 uses a local id never registered
  ingress::encode_samples(junk, std::vector<ingress::Record>{{0, 300, 4.0, 0}, {9, 300, 5.0, 0}},
                          [](uint32_t) { return ValueType::Float32; });
  EXPECT_FALSE(s.on_bytes(junk));
  EXPECT_EQ(c.ingress_malformed_frames, 1u);
  EXPECT_EQ(c.rej(Reject::Malformed), 1u);
  EXPECT_EQ(c.accepted, 4u);
  EXPECT_EQ(c.samples_in, c.accepted + c.rejected_total());
  b.shutdown();
  EXPECT_EQ(b.archiver().counters().archived.load(), 4u);
}

TEST(Broker, ConfigThenDataFramesFromStampedSamples) {
  FakeClock clock;
  FakeLink link;
  BrokerConfig cfg = test_config("data");
  Broker b(cfg, "key", clock, link);
  Config c;
  c.config_id = 1;
  c.topics = {{"usv.x", ValueType::Float32, 2, 40000}};
  c.streams = {{0, Aggregation::Max, 250000}, {0, Aggregation::Count, 500000}};
  ConfigAck ack = b.on_config(c);
  EXPECT_EQ(ack.status, 0);
  int64_t E = static_cast<int64_t>(ack.epoch_ns);
  EXPECT_EQ(E, clock.now_ns());
  IngressSession s(b);
  std::vector<ingress::Register> regs = {{0, ValueType::Float32, "usv.x"}};
  clock.set(E + 100 * kMs);
  ASSERT_TRUE(s.on_bytes(publisher_bytes(regs, {{0, 1, 5.0, 0}, {0, 2, 7.0, 0}})));
  // Stamped exactly at the boundary: belongs to the next window.
  clock.set(E + 250 * kMs);
  std::vector<uint8_t> more;
  ingress::encode_samples(more, std::vector<ingress::Record>{{0, 3, 100.0, 0}},
                          [](uint32_t) { return ValueType::Float32; });
  ASSERT_TRUE(s.on_bytes(more));
  ASSERT_EQ(link.writes.size(), 1u);
  std::vector<ValueKind> k1 = {value_kind(ValueType::Float32, Aggregation::Max)};
  Data d0 = decode_data(*split_frame(link.writes[0]), k1);
  EXPECT_EQ(d0.values[0].number, 7.0);
  b.tick(E + 500 * kMs);
  ASSERT_EQ(link.writes.size(), 2u);
  std::vector<ValueKind> k2 = {k1[0], value_kind(ValueType::Float32, Aggregation::Count)};
  Data d1 = decode_data(*split_frame(link.writes[1]), k2);
  EXPECT_EQ(d1.seq8, 1);
  EXPECT_EQ(d1.values[0].number, 100.0);
  EXPECT_EQ(d1.values[1].count, 3u);
  // STATUS rides in the same write as the next DATA frame.
  b.status_due(clock.now_ns());
  clock.set(E + 600 * kMs);
  ASSERT_TRUE(s.on_bytes(more));
  b.tick(E + 750 * kMs);
  ASSERT_EQ(link.writes.size(), 3u);
  auto f = split_frame(link.writes[2]);
  ASSERT_TRUE(f && is_data_type(f->type));
  auto st = split_frame(std::span(link.writes[2]).subspan(f->size));
  ASSERT_TRUE(st);
  auto status = std::get<Status>(decode(*st));
  EXPECT_EQ(status.counters[at(StatusField::SamplesIn)], 4u);
  EXPECT_EQ(status.counters[at(StatusField::ConfigId)], 1u);
  // With no DATA for a whole status period, STATUS goes out on its own.
  b.status_due(E + 800 * kMs);
  b.send_overdue_status(E + 900 * kMs);
  EXPECT_EQ(link.writes.size(), 3u);  // period is 0 here: never alone
  // Front buffers of 2: everything accepted reaches the archive at shutdown.
  b.shutdown();
  EXPECT_EQ(b.archiver().counters().archived.load(), 4u);
}

TEST(Broker, ConfigWithATypeClashIsRefused) {
  FakeClock clock;
  FakeLink link;
  Broker b(test_config("clash"), "key", clock, link);
  Config c;
  c.config_id = 5;
  c.topics = {{"usv.x", ValueType::Int, 2, 0}};
  EXPECT_EQ(b.on_config(c).status, static_cast<uint8_t>(ErrorCode::BadConfig));
}

TEST(Broker, TopicsAddedByConfigAreAcceptedFromEarlierRegistrations) {
  FakeClock clock;
  FakeLink link;
  Broker b(test_config("late"), "key", clock, link);
  IngressSession s(b);
  std::vector<ingress::Register> regs = {{0, ValueType::Float64, "usv.late"}};
  ASSERT_TRUE(s.on_bytes(publisher_bytes(regs, {{0, 1, 1.0, 0}})));
  EXPECT_EQ(b.counters().rej(Reject::UnknownTopic), 1u);
  Config c;
  c.config_id = 1;
  c.topics = {{"usv.late", ValueType::Float64, 2, 0}};
  b.on_config(c);
  std::vector<uint8_t> more;
  ingress::encode_samples(more, std::vector<ingress::Record>{{0, 2, 2.0, 0}},
                          [](uint32_t) { return ValueType::Float64; });
  ASSERT_TRUE(s.on_bytes(more));
  EXPECT_EQ(b.counters().accepted, 1u);
}

TEST(Broker, StatusGoesAloneOnlyWhenNoDataCarriesIt) {
  FakeClock clock;
  FakeLink link;
  Broker b(test_config("status"), "key", clock, link);
  b.on_config(status_config(3));
  int64_t t0 = clock.now_ns();
  b.status_due(t0);
  b.send_overdue_status(t0 + 500 * kMs);
  EXPECT_TRUE(link.writes.empty());
  b.send_overdue_status(t0 + 1000 * kMs);
  ASSERT_EQ(link.writes.size(), 1u);
  auto f = split_frame(link.writes[0]);
  ASSERT_TRUE(f);
  EXPECT_EQ(std::get<Status>(decode(*f)).counters[at(StatusField::ConfigId)], 3u);
  b.send_overdue_status(t0 + 3000 * kMs);
  EXPECT_EQ(link.writes.size(), 1u);  // sent once per period
}

TEST(Broker, InstrumentHealthRidesInStatusWhileItsPublisherIsConnected) {
  FakeClock clock;
  FakeLink link;
  Broker b(test_config("health"), "key", clock, link);
  b.on_config(status_config(4));
  auto status_now = [&] {
    link.writes.clear();
    b.status_due(clock.now_ns());
    b.send_overdue_status(clock.now_ns() + 2000 * kMs);
    return std::get<Status>(decode(*split_frame(link.writes.at(0))));
  };
  auto s = std::make_unique<IngressSession>(b);
  std::vector<uint8_t> bytes;
  ingress::encode_hello(bytes, {ingress::kVersion, "sensors"});
  ingress::encode_health(bytes, {{"gnss", {1, 10, 2, 0}}, {"ctd", {2, 5}}});
  ingress::encode_health(bytes, {{"gnss", {1, 12, 3, 1}}, {"ctd", {1, 6}}});  // replaces the first
  ASSERT_TRUE(s->on_bytes(bytes));
  std::vector<SensorHealth> want = {{"ctd", {1, 6}}, {"gnss", {1, 12, 3, 1}}};
  EXPECT_EQ(status_now().sensors, want);
  // A state change (the CTD unplugged) goes out at once, not at the next period (the last
  // change STATUS went, with status_now's, two seconds "later": within the change budget,
  // test_health.cpp).
  clock.advance(3000 * kMs);
  link.writes.clear();
  std::vector<uint8_t> unplugged;
  ingress::encode_health(unplugged, {{"gnss", {1, 13, 3, 1}}, {"ctd", {0, 6}}});
  ASSERT_TRUE(s->on_bytes(unplugged));
  ASSERT_EQ(link.writes.size(), 1u);
  EXPECT_EQ(std::get<Status>(decode(*split_frame(link.writes[0]))).sensors[0],
            (SensorHealth{"ctd", {0, 6}}));
  std::vector<uint8_t> counts_only;  // counters alone change: no STATUS of its own
  ingress::encode_health(counts_only, {{"gnss", {1, 14, 3, 1}}, {"ctd", {0, 6}}});
  ASSERT_TRUE(s->on_bytes(counts_only));
  EXPECT_EQ(link.writes.size(), 1u);
  s.reset();  // modd-sensors gone: its health is no longer reported as current
  EXPECT_TRUE(status_now().sensors.empty());
}

TEST(Broker, VanishingPublisherAndFullQueueAreCounted) {
  FakeClock clock;
  FakeLink link;
  BrokerConfig cfg = test_config("vanish");
  cfg.queue_limit_samples = 5;
  cfg.publisher_quota_samples = 100;  // the hard limit alone
  cfg.topic_quota_samples = 100;
  cfg.topics.push_back({"usv.big", ValueType::Float32, 100});  // no swap: the writer sees nothing
  Broker b(cfg, "key", clock, link);
  IngressSession s(b);
  std::vector<ingress::Register> regs = {{0, ValueType::Float32, "usv.big"}};
  std::vector<ingress::Record> recs;
  for (int i = 0; i < 8; ++i) recs.push_back({0, i, 1.0 * i, 0});
  ASSERT_TRUE(s.on_bytes(publisher_bytes(regs, recs)));
  EXPECT_EQ(b.counters().accepted, 5u);  // the queue limit: the rest is rejected, not lost
  EXPECT_EQ(b.counters().rej(Reject::Overflow), 3u);
  // Half a SAMPLES frame of 4 records, then the publisher is gone.
  std::vector<uint8_t> more;
  ingress::encode_samples(more, std::span(recs).first(4),
                          [](uint32_t) { return ValueType::Float32; });
  more.resize(more.size() / 2);
  ASSERT_TRUE(s.on_bytes(more));
  EXPECT_TRUE(s.on_close());
  EXPECT_EQ(b.counters().ingress_malformed_frames, 1u);
  EXPECT_EQ(b.counters().rej(Reject::Malformed), 4u);
  EXPECT_EQ(b.counters().samples_in, b.counters().accepted + b.counters().rejected_total());
  EXPECT_FALSE(s.on_close());
}

namespace {
// What the broker told a version-2 publisher.
struct Replies : ingress::ReplyHandler {
  std::vector<ingress::Catalogue> catalogues;
  std::vector<ingress::Ack> acks;
  std::vector<ingress::RejectMsg> rejects;
  void on_catalogue(const ingress::Catalogue& c) override { catalogues.push_back(c); }
  void on_ack(const ingress::Ack& a) override { acks.push_back(a); }
  void on_reject(const ingress::RejectMsg& r) override { rejects.push_back(r); }
  void feed(const std::vector<uint8_t>& b) {
    size_t used = 0;
    while (auto f = ingress::split_frame(std::span(b).subspan(used), ingress::kMaxFrame)) {
      used += f->size;
      ingress::decode_reply(*f, *this);
    }
    EXPECT_EQ(used, b.size());
  }
};

void wait_durable(Broker& b, uint64_t id) {
  for (int i = 0; i < 400 && b.archiver().counters().durable_flush.load() < id; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_GE(b.archiver().counters().durable_flush.load(), id);
}
}  // namespace

TEST(Broker, AFarFutureSampleIsRefusedAloneAndThePublisherToldWhy) {
  FakeClock clock;
  FakeLink link;
  BrokerConfig cfg = test_config("future");
  cfg.max_future_ms = 10'000;
  cfg.max_past_ms = 3'600'000;
  Broker b(cfg, "key", clock, link);
  IngressSession s(b);
  int64_t now = clock.now_ns();
  std::vector<ingress::Record> recs = {
      {0, 4'354'000'000'000'000'000, 1.0, 0}};  // 2107: a driver's unit error
  for (int i = 0; i < 20; ++i) recs.push_back({0, now - (20 - i) * kMs, 1.0 * i, 0});
  recs.push_back({0, now - 2 * 3'600'000 * kMs, 9.0, 0});  // two hours old
  ASSERT_TRUE(s.on_bytes(publisher_bytes({{0, ValueType::Float32, "usv.x"}}, recs)));
  EXPECT_EQ(b.counters().accepted, 20u);
  EXPECT_EQ(b.counters().rej(Reject::Timestamp), 2u);
  b.flush_buffers();
  wait_durable(b, 1);
  b.check_archive(now);
  Replies r;
  r.feed(s.take_output());
  ASSERT_EQ(r.catalogues.size(), 1u);
  EXPECT_EQ(r.catalogues[0].drone, "drone");
  EXPECT_EQ(r.catalogues[0].max_future_ms, 10'000u);
  ASSERT_EQ(r.catalogues[0].topics.size(), 2u);
  EXPECT_EQ(r.catalogues[0].topics[0].name, "usv.x");
  ASSERT_EQ(r.rejects.size(), 1u);
  EXPECT_EQ(r.rejects[0].reason, static_cast<uint8_t>(Reject::Timestamp));
  EXPECT_EQ(r.rejects[0].count, 2u);
  EXPECT_NE(r.rejects[0].detail.find("ahead of the broker clock"), std::string::npos)
      << r.rejects[0].detail;
  ASSERT_EQ(r.acks.size(), 1u);
  EXPECT_EQ(r.acks[0].received, 22u);
  EXPECT_EQ(r.acks[0].settled, 22u);
  EXPECT_EQ(r.acks[0].archived, 20u);
  b.shutdown();
  EXPECT_EQ(b.archiver().counters().archived.load(), 20u);
}

TEST(Broker, AClockJumpingBackBlocksNothing) {
  // The on-board clock set back two hours (a GPS or NTP correction): the publishers on the
  // same clock stamp with it at once. Their samples are judged against the clock as it reads
  // now (not against the stamps held since), so none is refused; the archive's log times
  // keep the broker's monotonic timeline (test_clock_step.cpp).
  FakeClock clock;
  FakeLink link;
  BrokerConfig cfg = test_config("jump");
  cfg.max_future_ms = 10'000;
  cfg.max_past_ms = 3'600'000;
  Broker b(cfg, "key", clock, link);
  IngressSession s(b);
  int64_t before = clock.now_ns();
  std::vector<ingress::Record> recs;
  for (int i = 0; i < 10; ++i) recs.push_back({0, before - (10 - i) * kMs, 1.0 * i, 0});
  ASSERT_TRUE(s.on_bytes(publisher_bytes({{0, ValueType::Float32, "usv.x"}}, recs)));
  int64_t after = before - 2 * 3'600'000 * kMs;  // two hours back: beyond max_past_ms
  clock.set(after);
  std::vector<ingress::Record> later;
  for (int i = 0; i < 10; ++i) later.push_back({0, after + i * kMs, 10.0 + i, 0});
  later.push_back(
      {0, before + 60'000 * kMs, 99.0, 0});  // a minute ahead of the old time: 2 h ahead now
  std::vector<uint8_t> bytes;
  ingress::encode_samples(bytes, later, [](uint32_t) { return ValueType::Float32; });
  ASSERT_TRUE(s.on_bytes(bytes));
  EXPECT_EQ(b.counters().accepted, 20u);
  EXPECT_EQ(b.counters().rej(Reject::Timestamp), 1u);
  b.shutdown();
  EXPECT_EQ(b.archiver().counters().archived.load(), 20u);
}

TEST(Broker, AFloodingPublisherLosesOnlyItsOwnSamples) {
  FakeClock clock;
  FakeLink link;
  BrokerConfig cfg = test_config("flood");
  cfg.queue_limit_samples = 100;
  cfg.topics = {{"usv.a", ValueType::Float32, 1000},
                {"usv.b", ValueType::Float32, 1000}};  // never swapped
  Broker b(cfg, "key", clock, link);
  IngressSession flooder(b), calm(b);
  b.counters().publishers_connected = 2;
  std::vector<ingress::Record> flood, normal;
  for (int i = 0; i < 200; ++i) flood.push_back({0, i, 1.0, 0});
  for (int i = 0; i < 20; ++i) normal.push_back({0, i, 2.0, 0});
  ASSERT_TRUE(flooder.on_bytes(publisher_bytes({{0, ValueType::Float32, "usv.a"}}, flood)));
  ASSERT_TRUE(calm.on_bytes(publisher_bytes({{0, ValueType::Float32, "usv.b"}}, normal)));
  EXPECT_EQ(calm.accepted(), 20u);
  EXPECT_EQ(calm.rejected(), 0u);
  EXPECT_EQ(flooder.accepted(), 50u);  // up to half the queue, then over its share (25)
  EXPECT_EQ(b.counters().rej(Reject::Quota), 150u);
  EXPECT_EQ(b.counters().samples_in, b.counters().accepted + b.counters().rejected_total());
}
