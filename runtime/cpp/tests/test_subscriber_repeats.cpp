// The C++ subscriber client passes each window once (docs/fleet.md): two
// stations (two SubBroker connections, each proving the delivery key) write the
// contracts' repeats (contracts/vectors/delivered_value.json); the callback gets
// every window once, and payloads without an identity from both. The control,
// keep_repeats, gets every line twice: the stations' copies did arrive.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "modd/client/subscriber.hpp"

using nlohmann::json;

namespace {

constexpr const char* kKey = "repeats-test-key";

// One SubBroker's delivery connection: answers the challenge, then writes lines.
class Station {
 public:
  explicit Station(uint16_t port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(port);
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
    std::string hello;
    char c = 0;
    while (::recv(fd_, &c, 1, 0) == 1 && c != '\n') hello.push_back(c);
    EXPECT_EQ(hello.rfind("MODD-DELIVERY/1 ", 0), 0u) << hello;
    send("AUTH " + modd::delivery_proof(kKey, hello.substr(16)));
  }
  ~Station() { ::close(fd_); }
  Station(const Station&) = delete;
  Station& operator=(const Station&) = delete;

  void send(const std::string& line) {
    std::string out = line + "\n";
    EXPECT_EQ(::send(fd_, out.data(), out.size(), MSG_NOSIGNAL), ssize_t(out.size()));
  }

 private:
  int fd_ = -1;
};

struct Received {
  std::mutex mu;
  std::vector<modd::Delivered> values;

  size_t size() {
    std::lock_guard<std::mutex> lock(mu);
    return values.size();
  }
  bool wait_for(size_t n) {
    for (int i = 0; i < 1000 && size() < n; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    return size() >= n;
  }
};

std::vector<std::string> repeat_lines(size_t* first) {
  std::ifstream f(std::string(MODD_CONTRACTS_DIR) + "/vectors/delivered_value.json");
  json v = json::parse(f);
  std::vector<std::string> lines;
  *first = 0;
  for (const auto& c : v["repeats"]["sequence"]) {
    lines.push_back(c["line"].get<std::string>());
    *first += c["first"].get<bool>() ? 1 : 0;
  }
  return lines;
}

// A window of the first line's subscription no line has: the end mark of station b.
std::string mark_of(const std::string& line) {
  json doc = json::parse(line);
  doc["window"] = 1000;
  return doc.dump();
}

// Station a writes every line, then station b every line and its mark; what the
// callback got and the client's stats.
std::pair<std::vector<modd::Delivered>, modd::Subscriber::Stats> two_stations(bool keep_repeats) {
  size_t first = 0;
  std::vector<std::string> lines = repeat_lines(&first);
  Received got;
  modd::Subscriber::Options options;
  options.key = kKey;
  options.keep_repeats = keep_repeats;
  modd::Subscriber sub(
      "127.0.0.1", 0,
      [&got](const modd::Delivered& d) {
        std::lock_guard<std::mutex> lock(got.mu);
        got.values.push_back(d);
      },
      options);
  sub.start();
  Station a(sub.port()), b(sub.port());
  for (const auto& line : lines) a.send(line);
  EXPECT_TRUE(got.wait_for(keep_repeats ? lines.size() : first));
  for (const auto& line : lines) b.send(line);
  b.send(mark_of(lines[0]));
  EXPECT_TRUE(got.wait_for((keep_repeats ? 2 * lines.size() : first + 2) + 1));
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // nothing more comes
  sub.stop();
  std::lock_guard<std::mutex> lock(got.mu);
  return {got.values, sub.stats()};
}

}  // namespace

TEST(SubscriberRepeats, TwoStationsGiveEachWindowOnce) {
  size_t first = 0;
  std::vector<std::string> lines = repeat_lines(&first);
  auto [values, stats] = two_stations(false);
  size_t without_identity = 0;
  for (const auto& line : lines) without_identity += json::parse(line).contains("window") ? 0 : 1;
  ASSERT_EQ(values.size(), first + without_identity + 1);
  EXPECT_EQ(stats.duplicates, (lines.size() - first) + (lines.size() - without_identity));
  EXPECT_EQ(stats.received, values.size());
  std::vector<std::tuple<std::string, std::string, std::string, int64_t, int64_t>> ids;
  for (const auto& d : values) {
    if (!d.has_identity) continue;
    auto id = std::make_tuple(d.drone, d.subscriber, d.period_s, d.epoch_ns, d.window);
    EXPECT_EQ(std::count(ids.begin(), ids.end(), id), 0) << d.subscriber << " " << d.window;
    ids.push_back(id);
  }
  EXPECT_EQ(values.back().window, 1000);  // b's mark, after b's copies
  EXPECT_EQ(ids.size(), first - without_identity + 1);
}

TEST(SubscriberRepeats, KeepRepeatsGivesBothStationsCopies) {
  size_t first = 0;
  std::vector<std::string> lines = repeat_lines(&first);
  auto [values, stats] = two_stations(true);
  EXPECT_EQ(values.size(), 2 * lines.size() + 1);
  EXPECT_EQ(stats.duplicates, 0u);
}

TEST(SubscriberRepeats, IdentityFieldsAreCheckedAndOptional) {
  const std::string base =
      R"({"subscriber":"s","topic":"usv.a.z","aggregation":"MIN","period_s":"1","unit":"M",)"
      R"("config_id":1,"slot":7,"start_ns":0,"end_ns":1,"value":1,"count":null,"delivered_ns":1)";
  modd::Delivered d;
  std::string err;
  ASSERT_TRUE(
      modd::parse_delivered(base + R"(,"drone":"usv","epoch_ns":null,"window":3})", d, &err));
  EXPECT_FALSE(d.has_identity);  // one of the three missing: no identity, passed on
  EXPECT_FALSE(modd::parse_delivered(base + R"(,"window":"3"})", d, &err));
  EXPECT_NE(err.find("window"), std::string::npos);
  EXPECT_FALSE(modd::parse_delivered(base + R"(,"drone":5})", d, &err));
  ASSERT_TRUE(modd::parse_delivered(
      base + R"(,"drone":"usv","epoch_ns":1700000000000000001,"window":-2})", d, &err));
  EXPECT_TRUE(d.has_identity);
  EXPECT_EQ(d.epoch_ns, 1700000000000000001);  // exact beyond a double's 53 bits
  EXPECT_EQ(d.window, -2);
}

TEST(SubscriberRepeats, SeenWindowsIsBoundedAndMergesRuns) {
  modd::SeenWindows seen(3, 2);
  for (int64_t k = 0; k < 10; k += 2) EXPECT_TRUE(seen.first("usv", "s", "1", 1, k));  // five runs
  EXPECT_TRUE(seen.first("usv", "s", "1", 1, 0));   // the oldest runs were forgotten
  EXPECT_FALSE(seen.first("usv", "s", "1", 1, 8));  // the newest kept
  EXPECT_TRUE(seen.first("usv", "s", "1", 1, 7));   // joins 8's run
  EXPECT_FALSE(seen.first("usv", "s", "1", 1, 7));
  EXPECT_TRUE(seen.first("usv", "s", "1", 2, 8));    // another epoch
  EXPECT_TRUE(seen.first("usv", "s", "0.5", 1, 8));  // another period: another grid
  EXPECT_TRUE(seen.first("usv", "t", "1", 1, 8));    // another subscriber
  EXPECT_TRUE(seen.first("usv", "u", "1", 1, 8));    // a third key: s, the least recent, forgotten
  EXPECT_FALSE(seen.first("usv", "t", "1", 1, 8));
  EXPECT_TRUE(seen.first("usv", "s", "1", 1, 8));
  EXPECT_TRUE(seen.first("usv", "s", "1", 1, INT64_MAX));
  EXPECT_TRUE(seen.first("usv", "s", "1", 1, INT64_MAX - 1));  // merges without overflow
  EXPECT_FALSE(seen.first("usv", "s", "1", 1, INT64_MAX));
  EXPECT_TRUE(seen.first("usv", "s", "1", 1, INT64_MIN));
  EXPECT_TRUE(seen.first("usv", "s", "1", 1, INT64_MIN + 1));
  EXPECT_FALSE(seen.first("usv", "s", "1", 1, INT64_MIN));
}
