// The C++ publisher client against a listening Unix socket played by the test.
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <thread>

#include "modd/client/publisher.hpp"
#include "modd/ingress/codec.hpp"

namespace {

struct Listener {
  int fd = -1;
  std::string path;
  explicit Listener(const std::string& p) : path(p) {
    ::unlink(p.c_str());
    fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::strncpy(a.sun_path, p.c_str(), sizeof a.sun_path - 1);
    EXPECT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    ::listen(fd, 4);
  }
  ~Listener() {
    ::close(fd);
    ::unlink(path.c_str());
  }
};

struct Sink : modd::ingress::Handler {
  std::string publisher;
  std::map<uint32_t, modd::ingress::Register> regs;
  std::vector<modd::ingress::Record> recs;
  void on_hello(const modd::ingress::Hello& h) override { publisher = h.publisher; }
  void on_register(const modd::ingress::Register& r) override { regs[r.local_id] = r; }
  bool type_of(uint32_t id, modd::link::ValueType& t) const override {
    auto it = regs.find(id);
    if (it == regs.end()) return false;
    t = it->second.type;
    return true;
  }
  void on_record(const modd::ingress::Record& r) override { recs.push_back(r); }
};

// Reads from fd until `want` records arrived or 5 s passed.
void read_records(int fd, Sink& s, size_t want, int64_t until_ts = -1) {
  std::vector<uint8_t> buf;
  auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  auto done = [&] {
    if (until_ts >= 0) return !s.recs.empty() && s.recs.back().timestamp_ns == until_ts;
    return s.recs.size() >= want;
  };
  while (!done() && std::chrono::steady_clock::now() < until) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 100) <= 0) continue;
    uint8_t b[4096];
    ssize_t n = ::read(fd, b, sizeof b);
    if (n <= 0) break;
    buf.insert(buf.end(), b, b + n);
    size_t at = 0;
    while (auto f = modd::ingress::split_frame(std::span(buf).subspan(at))) {
      at += f->size;
      modd::ingress::decode(*f, s);
    }
    buf.erase(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(at));
  }
}

}  // namespace

TEST(Publisher, SendsRegistrationsAndBatchesAndReconnects) {
  std::string path =
      (std::filesystem::temp_directory_path() / ("modd-pub-" + std::to_string(getpid()) + ".sock"))
          .string();
  Listener l(path);
  modd::Publisher pub("pub_1", "unix:" + path, {.connect_wait_ms = 100});
  pub.declare("usv.a.x", modd::ValueType::Float32);
  for (int i = 0; i < 100; ++i)
    EXPECT_TRUE(pub.publish("usv.a.x", int64_t{i}, static_cast<float>(i) * 0.5f));
  EXPECT_TRUE(pub.publish("usv.a.n", int64_t{7}, -3));  // a plain int: an int topic
  int c = ::accept(l.fd, nullptr, nullptr);
  ASSERT_GE(c, 0);
  Sink s;
  read_records(c, s, 101);
  EXPECT_EQ(s.publisher, "pub_1");
  ASSERT_EQ(s.recs.size(), 101u);
  EXPECT_EQ(s.regs.at(0).topic, "usv.a.x");
  EXPECT_EQ(s.regs.at(1).type, modd::link::ValueType::Int);
  EXPECT_EQ(s.recs[99].number, 49.5);
  EXPECT_EQ(s.recs[100].integer, -3);
  EXPECT_TRUE(pub.flush(std::chrono::seconds(2)));
  // The broker goes away; the client reconnects and registers again.
  ::close(c);
  for (int i = 0; i < 50 && pub.connected(); ++i) {
    pub.publish("usv.a.x", int64_t{1000 + i}, 1.0f);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  int c2 = ::accept(l.fd, nullptr, nullptr);
  ASSERT_GE(c2, 0);
  pub.publish("usv.a.x", int64_t{5000}, 2.0f);
  Sink s2;
  read_records(c2, s2, 1, 5000);  // samples kept across the reconnection come first
  EXPECT_GE(s2.recs.size(), 1u);
  EXPECT_EQ(s2.regs.at(0).topic, "usv.a.x");
  EXPECT_EQ(s2.recs.back().timestamp_ns, 5000);
  ::close(c2);
  auto st = pub.stats();
  EXPECT_GE(st.connects, 2u);
  EXPECT_EQ(st.dropped_bad_topic, 0u);
}

TEST(Publisher, QueueIsBoundedAndNeverBlocks) {
  modd::Publisher pub(
      "p", "unix:/nonexistent/dir/x.sock",
      {.queue_capacity = 10, .batch_max = 4, .reconnect_ms = 50, .connect_wait_ms = 0});
  auto t0 = std::chrono::steady_clock::now();
  int ok = 0;
  for (int i = 0; i < 1000; ++i) ok += pub.publish("t", int64_t{i}, 1.0);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(500));
  auto st = pub.stats();
  EXPECT_EQ(st.published + st.dropped_queue_full, 1000u);
  EXPECT_LE(st.published, 14u);
  EXPECT_FALSE(
      pub.publish("t", int64_t{5}, std::nan("")));  // refused at the call, before the queue
  EXPECT_EQ(pub.stats().dropped_bad_topic, 1u);
  EXPECT_EQ(pub.stats().refused_out_of_range, 1u);
}

TEST(Publisher, TheCatalogueRefusesAtTheCallAndResolvesShortNames) {
  std::string path =
      (std::filesystem::temp_directory_path() / ("modd-pubc-" + std::to_string(getpid()) + ".sock"))
          .string();
  Listener l(path);
  int c = -1;
  std::thread broker([&] {
    c = ::accept(l.fd, nullptr, nullptr);
    modd::ingress::Catalogue cat;
    cat.drone = "usv";
    cat.max_future_ms = 10'000;
    cat.max_past_ms = 60'000;
    cat.topics = {{"usv.accelerometer.accel_z", modd::link::ValueType::Float32},
                  {"usv.gps.fix", modd::link::ValueType::Bool},
                  {"usv.ctd.count", modd::link::ValueType::Int},
                  {"usv.a.temp", modd::link::ValueType::Float64},
                  {"usv.b.temp", modd::link::ValueType::Float64}};
    std::vector<uint8_t> out;
    modd::ingress::encode_catalogue(out, cat);
    ASSERT_EQ(::write(c, out.data(), out.size()), static_cast<ssize_t>(out.size()));
  });
  std::vector<std::string> errors;
  modd::Publisher pub(
      "pub_1", "unix:" + path,
      {.on_error = [&](const std::string&, const std::string& why) { errors.push_back(why); }});
  broker.join();
  ASSERT_GE(c, 0);
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  int64_t now = int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
  // The paper's Listing 2: short name, a double on a float32 topic.
  double value = 9.81;
  EXPECT_TRUE(pub.publish("accel_z", now, value));
  EXPECT_TRUE(pub.publish("accelerometer.accel_z", now, 1));  // an int on a float topic: converted
  EXPECT_TRUE(pub.publish("count", now, 2.6));                // rounded to 3
  EXPECT_TRUE(pub.publish("fix", now, 1));
  EXPECT_FALSE(pub.publish("fix", now, 2));         // a bool takes 0 or 1
  EXPECT_FALSE(pub.publish("accel_zz", now, 1.0));  // unknown
  EXPECT_NE(pub.last_error().find("unknown topic 'accel_zz'"), std::string::npos)
      << pub.last_error();
  EXPECT_NE(pub.last_error().find("usv.accelerometer.accel_z"),
            std::string::npos);                 // says what exists
  EXPECT_FALSE(pub.publish("temp", now, 1.0));  // ambiguous
  EXPECT_NE(pub.last_error().find("ambiguous"), std::string::npos);
  EXPECT_FALSE(pub.publish("accel_z", now, 1e39));                         // beyond float32
  EXPECT_FALSE(pub.publish("count", now, uint64_t{1} << 63));              // beyond int64
  EXPECT_FALSE(pub.publish("accel_z", now + 3'600'000'000'000'000, 1.0));  // an hour ahead
  auto st = pub.stats();
  EXPECT_EQ(st.published, 4u);
  EXPECT_EQ(st.refused_unknown_topic, 2u);
  EXPECT_EQ(st.refused_out_of_range, 3u);
  EXPECT_EQ(st.refused_timestamp, 1u);
  EXPECT_EQ(st.dropped_bad_topic, 6u);
  EXPECT_EQ(errors.size(), 6u);  // once per topic and reason
  Sink s;
  read_records(c, s, 4);
  ASSERT_EQ(s.recs.size(), 4u);
  EXPECT_EQ(s.regs.at(0).topic, "usv.accelerometer.accel_z");
  EXPECT_EQ(s.regs.at(0).type, modd::link::ValueType::Float32);
  EXPECT_FLOAT_EQ(static_cast<float>(s.recs[0].number), 9.81f);
  EXPECT_EQ(s.recs[1].number, 1.0);
  EXPECT_EQ(s.recs[2].integer, 3);
  EXPECT_EQ(s.recs[3].integer, 1);
  ::close(c);
}
