// MoDD subscriber client (C++): receives a subscriber's values over the
// SubBroker's TCP delivery (docs/subbroker.md: the SubBroker connects to the
// subscriber's endpoint and writes one JSON object per line) and calls back
// once per delivered value. Self-contained (this header and subscriber.cpp,
// standard library and POSIX only), like the publisher client.
//
//   modd::Subscriber sub("127.0.0.1", 7405, [](const modd::Delivered& d) {
//     if (d.present) std::printf("%s %s = %g\n", d.topic.c_str(), d.aggregation.c_str(), d.value);
//   });
//   sub.run();  // until sub.stop() from another thread or a signal handler
//
// Callbacks run on the thread that runs run(); a slow callback delays only
// this subscriber (the SubBroker keeps a bounded queue per subscriber and drops
// its oldest values, never blocking the link).
//
// Only the SubBroker may deliver (docs/subbroker.md, "TCP delivery"): on each
// connection the subscriber sends a challenge, "MODD-DELIVERY/1 <nonce>\n", and
// accepts value lines only after the answer "AUTH <HMAC-SHA256(key, ...)>\n"
// proves that the peer holds the delivery key. Several connections are served
// at once (poll); one that does not prove itself within the handshake timeout,
// or stays idle past the idle timeout, is dropped, so an idle or hostile socket
// never holds back the SubBroker's values.
//
// Each window reaches the callback once (docs/fleet.md, "A window's identity"):
// a value whose identity (drone, subscriber, epoch_ns, window, with its period)
// came before, from this SubBroker or another station's, is dropped and counted
// (Stats::duplicates); a value without an identity (an older SubBroker) passes.
#pragma once
#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace modd {

// One window of one subscription.
struct Delivered {
  std::string subscriber, topic, aggregation, period_s, unit;
  uint64_t config_id = 0;
  uint64_t slot = 0;
  int64_t start_ns = 0, end_ns = 0;  // the window [start, end), ns since the Unix epoch
  int64_t delivered_ns = 0;
  bool present = false;        // false: no sample in the window
  double value = 0;            // the aggregate (bools as 0/1); unset for ALL
  std::vector<double> values;  // ALL: every raw sample of the window
  int64_t count = -1;          // samples behind the value, when known; else -1
  bool backfilled = false;     // recomputed from the drone's archive after the link missed it
  // The window's identity with `subscriber` (docs/fleet.md); has_identity false
  // when the payload lacks one of the three (an older SubBroker).
  bool has_identity = false;
  std::string drone;
  int64_t epoch_ns = 0;  // the epoch of the configuration the window belongs to
  int64_t window = 0;    // its index on that configuration's grid
};

// Parses one delivered line. On malformed input returns false and says why.
bool parse_delivered(std::string_view line, Delivered& out, std::string* error = nullptr);

// The delivery key shared by the SubBroker and its TCP subscribers. Resolved as
// the SubBroker does: $MODD_DELIVERY_KEY when set (a reference: "env:NAME" or
// "file:PATH"), else the file $XDG_CONFIG_HOME/modd/delivery.key (default
// ~/.config/modd/delivery.key), created with a random key (mode 0600) when
// absent. A key file must be a regular file of at most 4 KiB. Throws
// std::runtime_error naming the reference.
std::string load_delivery_key();

// The windows a subscriber has had, by identity: runs of consecutive window
// indices per (drone, subscriber, period) and epoch (live windows come in order,
// so an hour of them is one run). The period is compared too: a subscription
// made again under its name with another period numbers its windows on another
// grid. Bounded: at most max_runs runs per key, the oldest (lowest epoch, then
// window) forgotten first, and at most max_keys keys, the least recently heard
// forgotten first; a forgotten window passes again. One thread at a time (the
// Subscriber's).
//
//   modd::SeenWindows seen;
//   seen.first(d);  // true: d is new (now remembered), or has no identity
class SeenWindows {
 public:
  static constexpr size_t kMaxRuns = 1024, kMaxKeys = 1024;
  explicit SeenWindows(size_t max_runs = kMaxRuns, size_t max_keys = kMaxKeys);
  bool first(const Delivered& d);
  bool first(const std::string& drone, const std::string& subscriber, const std::string& period_s,
             int64_t epoch_ns, int64_t window);

 private:
  struct Runs {
    std::map<std::pair<int64_t, int64_t>, int64_t> last;  // (epoch, first window) -> last window
    uint64_t used = 0;
  };
  using Key = std::array<std::string, 3>;  // drone, subscriber, period_s
  Runs& runs_of(Key key);

  std::map<Key, Runs> keys_;
  size_t max_runs_, max_keys_;
  uint64_t tick_ = 0;
};

using Digest = std::array<uint8_t, 32>;
Digest sha256(std::string_view data);
Digest hmac_sha256(std::string_view key, std::string_view data);
// The SubBroker's answer to a challenge: lowercase hex of
// HMAC-SHA256(key, "modd-delivery/1\n" + nonce_hex).
std::string delivery_proof(std::string_view key, std::string_view nonce_hex);

class Subscriber {
 public:
  using Callback = std::function<void(const Delivered&)>;
  struct Stats {
    uint64_t received = 0;   // values passed to the callback
    uint64_t malformed = 0;  // lines that did not parse (skipped)
    uint64_t connections = 0;
    uint64_t refused = 0;     // connections dropped: no or wrong proof, idle, over the limit
    uint64_t duplicates = 0;  // windows had before (SeenWindows), not passed to the callback
  };
  struct Options {
    std::string key;                  // the delivery key; empty: load_delivery_key()
    int handshake_timeout_ms = 5000;  // to prove itself, from accept
    int idle_timeout_ms = 300000;     // without a byte, once proven
    size_t max_connections = 8;       // at once; past it the oldest unproven one is dropped
    bool keep_repeats = false;        // true: every value to the callback, repeats included
  };

  // Listens on host:port, the subscriber's endpoint in the model (port 0: any).
  // Throws std::runtime_error when the endpoint cannot be bound or the key loaded.
  Subscriber(const std::string& host, uint16_t port, Callback callback);
  Subscriber(const std::string& host, uint16_t port, Callback callback, Options options);
  ~Subscriber();
  Subscriber(const Subscriber&) = delete;
  Subscriber& operator=(const Subscriber&) = delete;

  void run();            // serves until stop()
  void start();          // run() on a background thread
  void stop() noexcept;  // safe from any thread and from a signal handler
  uint16_t port() const noexcept { return port_; }
  Stats stats() const noexcept;

 private:
  struct Connection;
  void accept_one(std::vector<Connection>& conns);
  bool serve(Connection& c);  // false: drop the connection
  bool handle_line(Connection& c, std::string_view line);

  Callback callback_;
  Options options_;
  int listen_fd_ = -1;
  int wake_[2] = {-1, -1};
  uint16_t port_ = 0;
  std::atomic<bool> stopping_{false};
  SeenWindows seen_;  // run()'s thread only
  std::atomic<uint64_t> received_{0}, malformed_{0}, connections_{0}, refused_{0}, duplicates_{0};
  std::thread thread_;
};

}  // namespace modd
