// The PubBroker's backfill: windows recomputed from an archive the Archiver wrote,
// compared with an Accumulator fed the same samples directly; resume points;
// the pace (token bucket) and the live guard.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <map>
#include <random>

#include "modd/archive/archiver.hpp"
#include "modd/archive/reader.hpp"
#include "modd/broker/backfill.hpp"
#include "modd/broker/dgram_link.hpp"

using namespace modd;
using namespace modd::broker;
namespace bf = modd::link::backfill;

namespace {

constexpr int64_t kT0 = 1'763'700'000'000'000'000;

struct Fixture {
  std::string dir;
  std::vector<archive::Sample> samples;  // 25 Hz with jitter, 60 s, float32 values
  explicit Fixture(const std::string& name, size_t rotate_bytes = 256u << 20) {
    dir =
        (std::filesystem::temp_directory_path() / ("modd-bf-" + name + std::to_string(::getpid())))
            .string();
    std::filesystem::remove_all(dir);
    std::mt19937 rng(7);
    std::uniform_int_distribution<int64_t> jitter(0, 9'000'000);
    std::uniform_real_distribution<float> val(-20, 20);
    for (int64_t i = 0; i < 25 * 60; ++i)
      samples.push_back({kT0 + i * 40'000'000 + jitter(rng), 0, static_cast<double>(val(rng)), 0});
    archive::ArchiverOptions o;
    o.dir = dir;
    o.writer.chunk_bytes = 4096;  // many chunks: the reader crosses chunk borders
    o.rotate_bytes = rotate_bytes;
    archive::Archiver a(o);
    auto topic = std::make_shared<const archive::TopicInfo>(
        archive::TopicInfo{"usv.imu.x", link::ValueType::Float32});
    auto other = std::make_shared<const archive::TopicInfo>(
        archive::TopicInfo{"usv.imu.y", link::ValueType::Float32});
    for (size_t at = 0; at < samples.size(); at += 25) {
      std::vector<archive::Sample> part(
          samples.begin() + static_cast<long>(at),
          samples.begin() + static_cast<long>(std::min(at + 25, samples.size())));
      a.submit(other, std::vector<archive::Sample>(part));  // interleaved channel, to be skipped
      a.submit(topic, std::move(part));
    }
    a.stop();
  }
  ~Fixture() { std::filesystem::remove_all(dir); }
  link::Value expected(link::Aggregation agg, int64_t s, int64_t e) const {
    Accumulator acc(link::ValueType::Float32, agg);
    for (const auto& x : samples)
      if (x.stamp_ns >= s && x.stamp_ns < e) acc.add(x.number, 0);
    return acc.take();
  }
};

bf::Request request(link::Aggregation agg, uint64_t windows, uint64_t resume, uint64_t rate) {
  bf::Request r;
  r.request_id = 5;
  r.topic = "usv.imu.x";
  r.type = link::ValueType::Float32;
  r.aggregation = agg;
  r.period_us = 250'000;
  r.from_ns = kT0 - 100'000'000;
  r.windows = windows;
  r.resume = resume;
  r.rate_bps = rate;
  return r;
}

// Runs the sender in simulated time until END; returns the windows by index and the frames' times.
struct Outcome {
  std::map<uint64_t, link::Value> windows;
  std::vector<std::pair<int64_t, size_t>> sent;  // (time, bytes of the write)
  std::vector<size_t> data_bytes;                // of its BACKFILL_DATA frame
  bf::EndStatus status = bf::EndStatus::Io;
  int duplicates = 0;
};

Outcome run(BackfillSender& s, const bf::Request& r, int64_t live_period_ns = 0) {
  Outcome out;
  std::vector<uint8_t> reply;
  s.on_request(r, link::ValueType::Float32, reply);
  // accepted: acknowledged at once by a PROGRESS at the resume point
  auto ack = std::get<bf::Progress>(bf::decode(*link::split_frame(reply)));
  EXPECT_EQ(ack.request_id, r.request_id);
  EXPECT_EQ(ack.next, r.resume);
  link::ValueKind kind = link::value_kind(r.type, r.aggregation);
  int64_t now = kT0 + 3600'000'000'000;
  for (int step = 0; step < 2'000'000 && s.active(); ++step) {
    BackfillSender::Env env{
        now, now, live_period_ns ? (now / live_period_ns + 1) * live_period_ns : INT64_MAX, true};
    std::vector<std::vector<uint8_t>> frames;
    s.pump(env, frames);
    for (const auto& f : frames) {
      out.sent.emplace_back(now, f.size());
      out.data_bytes.push_back(0);
      size_t at = 0;
      while (auto raw = link::split_frame(std::span(f).subspan(at))) {
        at += raw->size;
        if (raw->type == static_cast<uint8_t>(bf::Type::Data)) {
          out.data_bytes.back() += raw->size;
          auto d = bf::decode_data(*raw, kind);
          for (size_t i = 0; i < d.values.size(); ++i)
            if (!out.windows.emplace(d.first + i, d.values[i]).second) ++out.duplicates;
        } else {
          bf::Message m = bf::decode(*raw);
          if (auto* e = std::get_if<bf::End>(&m)) out.status = e->status;
        }
      }
    }
    now = std::max(now + 1'000'000, s.next_wake_ns(now));
  }
  return out;
}

}  // namespace

TEST(BackfillSender, WindowsEqualTheLiveAccumulatorOverTheArchive) {
  Fixture fx("eq", 64 * 1024);  // several files too
  for (auto agg : {link::Aggregation::Min, link::Aggregation::Average, link::Aggregation::All,
                   link::Aggregation::Count}) {
    BackfillSender s(fx.dir, "modd", 100000);
    auto r = request(agg, 250, 0, 0);
    Outcome out = run(s, r);
    EXPECT_EQ(out.status, bf::EndStatus::Done);
    EXPECT_EQ(out.duplicates, 0);
    ASSERT_EQ(out.windows.size(), 250u);
    for (uint64_t k = 0; k < 250; ++k) {
      int64_t st = r.window_start_ns(k);
      link::Value want = fx.expected(agg, st, st + 250'000'000);
      const link::Value& got = out.windows[k];
      ASSERT_EQ(got.present, want.present) << k;
      if (!want.present) continue;
      EXPECT_FLOAT_EQ(static_cast<float>(got.number), static_cast<float>(want.number)) << k;
      EXPECT_EQ(got.count, want.count) << k;
      if (agg == link::Aggregation::All) {
        ASSERT_EQ(got.numbers.size(), want.numbers.size());
        for (size_t i = 0; i < want.numbers.size(); ++i) EXPECT_EQ(got.numbers[i], want.numbers[i]);
      }
    }
  }
}

// An event stream's windows equal the live path's: one detector fed every sample from
// the config's epoch (state_from_ns) on, its window taken at each window's end. Resumed
// in the middle, the sender rebuilds the detector's state by replaying the archive (here
// in steps of 7 samples), so the windows after the resume point are the same.
static void check_events(link::Aggregation agg, const link::EventParams& p) {
  Fixture fx(std::string("ev") + std::to_string(static_cast<int>(agg)), 64 * 1024);
  bf::Request r = request(agg, 250, 0, 0);
  r.event = p;
  r.state_from_ns = static_cast<uint64_t>(kT0 - 600'000'000);
  r.from_ns = static_cast<uint64_t>(kT0 + 1'000'000'000);  // the state holds 1.6 s of samples
  EventDetector live(event_spec(agg, p));
  std::map<uint64_t, link::Value> want;
  size_t at = 0;
  for (uint64_t k = 0; k < r.windows; ++k) {
    int64_t s = r.window_start_ns(k), e = s + 250'000'000;
    for (; at < fx.samples.size() && fx.samples[at].stamp_ns < e; ++at)
      live.add(fx.samples[at].stamp_ns, fx.samples[at].number);
    EventWindow w = live.take();
    if (k > 0) want[k] = event_value(w, s, true);  // window 0 holds earlier samples too
  }
  size_t events = 0;
  for (uint64_t resume : {uint64_t{1}, uint64_t{137}}) {
    BackfillSender s(fx.dir, "modd", 100000);
    s.set_replay_step(7);
    r.resume = resume;
    Outcome out = run(s, r);
    EXPECT_EQ(out.status, bf::EndStatus::Done);
    EXPECT_EQ(out.duplicates, 0);
    ASSERT_EQ(out.windows.size(), r.windows - resume);
    for (uint64_t k = resume; k < r.windows; ++k) {
      const link::Value& got = out.windows[k];
      ASSERT_EQ(got.present, want[k].present) << k;
      EXPECT_EQ(got.numbers, want[k].numbers) << k;
      EXPECT_EQ(got.times_us, want[k].times_us) << k;
      EXPECT_EQ(got.coalesced, want[k].coalesced) << k;
      events += got.numbers.size();
    }
  }
  EXPECT_GT(events, 50u);  // the comparison is not vacuous
}

TEST(BackfillSender, EventWindowsEqualTheLiveDetectorFromTheEpoch) {
  link::EventParams on_change;
  on_change.deadband = 15;  // uniform -20..20: about a quarter of the samples
  on_change.max_events = 2;
  check_events(link::Aggregation::OnChange, on_change);
  link::EventParams threshold;
  threshold.code = static_cast<uint8_t>(link::events::Crossing::Up);
  threshold.level = 0;
  threshold.hysteresis = 12;
  threshold.max_events = 1;
  check_events(link::Aggregation::Threshold, threshold);
}

TEST(BackfillSender, ResumeSendsOnlyTheRest) {
  Fixture fx("resume");
  BackfillSender s(fx.dir, "modd", 100000);
  Outcome out = run(s, request(link::Aggregation::Max, 200, 137, 0));
  EXPECT_EQ(out.status, bf::EndStatus::Done);
  EXPECT_EQ(out.windows.size(), 63u);
  EXPECT_EQ(out.windows.begin()->first, 137u);
  EXPECT_EQ(out.duplicates, 0);
}

// The pace counts each frame with the bytes the link adds to it (`overhead`; 0: the
// default, kSegmentOverhead for tcp).
static void check_pace(const std::string& name, size_t overhead) {
  const uint64_t rate = 1200;
  const size_t head = overhead ? overhead : BackfillSender::kSegmentOverhead;
  for (int64_t live_period : {int64_t{250'000'000}, int64_t{0}}) {
    Fixture fx(name + (live_period ? "-live" : ""));
    BackfillSender s(fx.dir, "modd", 100000);
    if (overhead) s.set_frame_overhead(overhead);
    EXPECT_EQ(s.frame_overhead(), head);
    Outcome out = run(s, request(link::Aggregation::All, 240, 0, rate), live_period);
    EXPECT_EQ(out.status, bf::EndStatus::Done);
    size_t biggest = 0;
    for (auto& [t, n] : out.sent) biggest = std::max(biggest, n + head);
    // Every 1 s interval starting at a frame: bytes (with the link's overhead) <= rate + one frame.
    for (size_t i = 0; i < out.sent.size(); ++i) {
      size_t bytes = 0;
      for (size_t j = i;
           j < out.sent.size() && out.sent[j].first < out.sent[i].first + 1'000'000'000; ++j)
        bytes += out.sent[j].second + head;
      EXPECT_LE(bytes, rate + biggest) << "interval starting at frame " << i;
    }
    size_t total = 0;
    for (auto& [t, n] : out.sent) total += n + head;
    double secs = static_cast<double>(out.sent.back().first - out.sent.front().first) / 1e9;
    if (!live_period) {
      // Nothing else on the link: the whole run takes what the rate allows.
      EXPECT_NEAR(secs, static_cast<double>(total) / rate,
                  0.1 * static_cast<double>(total) / rate + 0.5);
      continue;
    }
    // Live slots every 250 ms: no slower than what the rate allows plus the guards' gaps.
    EXPECT_GE(secs, 0.9 * static_cast<double>(total) / rate - 0.5);
    // Live guard: no frame goes in the last moments before a live slot (period 250 ms).
    for (size_t i = 0; i < out.sent.size(); ++i) {
      if (!out.data_bytes[i]) continue;
      int64_t to_slot = live_period - out.sent[i].first % live_period;
      EXPECT_GE(static_cast<double>(to_slot),
                std::min((out.data_bytes[i] + head) * 1e9 / rate, 1e8) * 0.99);
    }
  }
}

TEST(BackfillSender, PaceNeverExceedsTheRateByMoreThanOneFrame) { check_pace("pace", 0); }

// A serial link adds 17 bytes to a frame, not a TCP segment's 52: the pace counts those,
// so the same rate carries more windows per second.
TEST(BackfillSender, PaceCountsTheLinksOwnOverhead) {
  check_pace("pace-serial", broker::control_frame_overhead(true));
  check_pace("pace-udp", broker::control_frame_overhead(false));
  auto seconds = [](const std::string& name, size_t overhead) {
    Fixture fx(name);
    BackfillSender s(fx.dir, "modd", 100000);
    s.set_frame_overhead(overhead);
    Outcome out = run(s, request(link::Aggregation::Max, 400, 0, 400));
    EXPECT_EQ(out.status, bf::EndStatus::Done);
    return static_cast<double>(out.sent.back().first - out.sent.front().first) / 1e9;
  };
  double tcp = seconds("pace-tcp-max", BackfillSender::kSegmentOverhead);
  double serial = seconds("pace-serial-max", broker::control_frame_overhead(true));
  EXPECT_LT(serial, 0.8 * tcp) << "tcp " << tcp << " s, serial " << serial << " s";
}

TEST(BackfillSender, WaitsForWindowsNotYetArchived) {
  Fixture fx("wait");
  BackfillSender s(fx.dir, "modd", 100000);
  std::vector<uint8_t> reply;
  auto r = request(link::Aggregation::Min, 100, 0, 0);
  s.on_request(r, std::nullopt, reply);
  BackfillSender::Env env{kT0 + 3600'000'000'000, r.window_start_ns(10), INT64_MAX, true};
  std::vector<std::vector<uint8_t>> frames;
  for (int i = 0; i < 100; ++i) {
    s.pump(env, frames);
    env.now += 100'000'000;
  }
  uint64_t last = 0;
  for (const auto& f : frames) {
    auto raw = link::split_frame(f);
    if (raw->type != static_cast<uint8_t>(bf::Type::Data)) continue;
    auto d = bf::decode_data(*raw, link::value_kind(r.type, r.aggregation));
    last = d.first + d.values.size();
  }
  EXPECT_EQ(last, 10u);  // windows 0..9 end at or before the horizon (window 10 ends after it)
  EXPECT_EQ(s.active(), 1u);
}

TEST(BackfillSender, RefusesAWrongTypeAndCancels) {
  Fixture fx("refuse");
  BackfillSender s(fx.dir, "modd", 1000);
  std::vector<uint8_t> reply;
  s.on_request(request(link::Aggregation::Min, 10, 0, 0), link::ValueType::Int, reply);
  auto m = bf::decode(*link::split_frame(reply));
  EXPECT_EQ(std::get<bf::End>(m).status, bf::EndStatus::BadRequest);
  reply.clear();
  s.on_request(request(link::Aggregation::Min, 10, 0, 0), std::nullopt, reply);
  EXPECT_EQ(s.active(), 1u);
  EXPECT_EQ(std::get<bf::Progress>(bf::decode(*link::split_frame(reply))).bytes_sent, 0u);
  reply.clear();
  s.on_cancel(5, reply);
  EXPECT_EQ(s.active(), 0u);
  EXPECT_EQ(std::get<bf::End>(bf::decode(*link::split_frame(reply))).status,
            bf::EndStatus::Cancelled);
}

TEST(BackfillSender, FramesFitTheDatagramLinksPacket) {
  Fixture fx("cap");
  for (auto agg : {link::Aggregation::Average, link::Aggregation::Min, link::Aggregation::Count}) {
    BackfillSender s(fx.dir, "modd", 100000);
    s.set_max_datagram(100);  // a fast pace (frames of ~6 KB) on a link of 100-byte datagrams
    Outcome out = run(s, request(agg, 240, 0, 100000));
    EXPECT_EQ(out.status, bf::EndStatus::Done);
    EXPECT_EQ(out.windows.size(), 240u);
    EXPECT_EQ(out.duplicates, 0);
    size_t frames = 0;
    for (size_t n : out.data_bytes) {
      if (!n) continue;
      ++frames;
      EXPECT_LE(n + 19, 100u);  // the CONTROL datagram: type, counter varint, frame, tag
    }
    EXPECT_GT(frames, 5u);
  }
}
