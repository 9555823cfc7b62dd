// MoDD publisher client: hands samples to the on-board PubBroker over its
// local ingress (docs/ingress.md, protocol version 2). Self-contained (this
// header and publisher.cpp, standard library and POSIX only) so that an
// integrator can add it to their own CMake project.
//
//   modd::Publisher pub("pub_1", "unix:/run/modd/ingress.sock");
//   pub.publish("accel_z", now_ns(), 9.81);   // the paper's Listing 2: short name, any number
//   if (!pub.publish("acel_z", now_ns(), 1.0)) std::puts(pub.last_error().c_str());
//
// The contract (docs/ingress.md, "The publisher contract"):
// * The broker sends the drone's topic catalogue when the client connects (the constructor
//   waits up to Options::connect_wait_ms for it). With it, publish() refuses at the call,
//   returning false, counting it and logging it once per topic and reason, what the broker
//   would refuse: an unknown (or ambiguous short) topic name, a value that does not fit the
//   declared type, a timestamp beyond the broker's bounds. A short name (the last part, or
//   any dotted suffix, of a topic's full name) is accepted when exactly one topic matches.
// * Any arithmetic value is converted to the topic's declared type: to float32 when finite
//   and within ±FLT_MAX (rounded to nearest), to float64 when finite, to int when finite and
//   within int64 after rounding to nearest (ties away from zero), to bool from 0 or 1 only.
//   Anything else is refused (refused_out_of_range / refused_not_finite).
// * publish() never blocks on the network and never throws: it appends to a bounded queue
//   that a background thread sends in batches; a full queue drops and counts.
// * stats() tells apart what was accepted at the call (published), written to the socket
//   (sent), acknowledged on disk by the broker (on_disk), refused by the broker
//   (rejected_by_broker, with the reason logged once). Samples sent but not yet on disk are
//   kept and sent again after a reconnection (a broker restart): at least once.
#pragma once
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <type_traits>
#include <unordered_map>
#include <vector>

namespace modd {

enum class ValueType : uint8_t { Float32 = 0, Float64 = 1, Int = 2, Bool = 3 };

class Publisher {
 public:
  struct Options {
    size_t queue_capacity = 65536;   // samples waiting to be sent
    size_t batch_max = 256;          // records per SAMPLES frame
    int reconnect_ms = 200;          // wait between connection attempts (the first one at once)
    int connect_wait_ms = 1000;      // the constructor waits this long for the topic catalogue
    size_t replay_capacity = 65536;  // samples sent but not yet on disk kept for a resend
    // Called (from the caller's thread or the client's) the first time a topic is refused
    // for a reason, at the call or by the broker. Default: one line on stderr.
    std::function<void(const std::string& topic, const std::string& why)> on_error;
  };
  struct Stats {
    uint64_t published = 0;           // accepted at the call into the queue
    uint64_t sent = 0;                // written to the broker's socket (replays included)
    uint64_t on_disk = 0;             // acknowledged by the broker as in the archive file
    uint64_t rejected_by_broker = 0;  // refused by the broker (REJECT), reason logged
    uint64_t dropped_queue_full = 0;
    uint64_t dropped_bad_topic = 0;  // refused at the call, every reason (the four below)
    uint64_t refused_unknown_topic = 0;
    uint64_t refused_wrong_type = 0;
    uint64_t refused_out_of_range = 0;  // includes NaN/inf
    uint64_t refused_timestamp = 0;
    uint64_t dropped_at_close = 0;  // still queued when destroyed with no broker
    uint64_t replayed = 0;          // sent again after a reconnection (not yet on disk before)
    uint64_t replay_dropped = 0;    // not yet on disk but pushed out of the replay buffer
    uint64_t connects = 0;
  };

  // ingress: "unix:/path/to/socket" or "tcp:127.0.0.1:7373".
  Publisher(std::string name, std::string ingress);
  Publisher(std::string name, std::string ingress, Options options);
  ~Publisher();  // sends what is queued and waits for it on disk (up to 2 s), then disconnects
  Publisher(const Publisher&) = delete;
  Publisher& operator=(const Publisher&) = delete;

  // Declares a topic's type; without it, the catalogue (or else the first publish) decides.
  void declare(const std::string& topic, ValueType type) noexcept;
  bool publish(const std::string& topic, int64_t timestamp_ns, float value) noexcept;
  bool publish(const std::string& topic, int64_t timestamp_ns, double value) noexcept;
  bool publish(const std::string& topic, int64_t timestamp_ns, int64_t value) noexcept;
  bool publish(const std::string& topic, int64_t timestamp_ns, bool value) noexcept;
  // Any other arithmetic type (int, unsigned, long double, uint8_t, ...).
  template <typename T>
  requires(std::is_arithmetic_v<T> && !std::is_same_v<T, bool> && !std::is_same_v<T, int64_t> &&
           !std::is_same_v<T, float> &&
           !std::is_same_v<T, double>) bool publish(const std::string& topic, int64_t timestamp_ns,
                                                    T value) noexcept {
    if constexpr (std::is_floating_point_v<T>)
      return publish(topic, timestamp_ns, static_cast<double>(value));
    else if constexpr (std::is_signed_v<T>)
      return publish(topic, timestamp_ns, static_cast<int64_t>(value));
    else
      return push(topic, timestamp_ns, In{In::Unsigned, 0, 0, static_cast<uint64_t>(value)});
  }
  // Waits until the queue is empty and written (true) or the timeout passes.
  bool flush(std::chrono::milliseconds timeout) noexcept;
  // Waits until every sample sent is acknowledged on disk (or refused) by the broker.
  bool wait_on_disk(std::chrono::milliseconds timeout) noexcept;
  bool connected() const noexcept;
  Stats stats() const noexcept;
  std::string last_error() const noexcept;  // the latest refusal, in words

 private:
  struct In {
    enum Kind : uint8_t { Float32, Float64, Signed, Unsigned, Bool } kind;
    double d;
    int64_t i;
    uint64_t u;
  };
  struct Record {
    uint32_t id;
    int64_t ts;
    double number;
    int64_t integer;
  };
  struct Topic {
    std::string name;
    ValueType type;
  };
  struct Catalogue {
    bool known = false;
    std::string drone;
    uint64_t max_future_ms = 0, max_past_ms = 0;
    bool accept_unknown = false;
    std::map<std::string, ValueType> topics;
  };
  bool push(const std::string& topic, int64_t ts, In v) noexcept;
  bool refuse(const std::string& topic, uint64_t Stats::*counter, const std::string& why);
  bool resolve(const std::string& given, std::string& full, std::string& why) const;
  void run();
  bool connect_and_hello();
  bool send_all(const std::vector<uint8_t>& bytes);
  void read_replies();
  void handle_reply(uint8_t type, const uint8_t* p, size_t n);
  void disconnect();
  void report(const std::string& topic, const std::string& why);

  std::string name_, ingress_;
  Options opt_;
  mutable std::mutex mu_;
  std::condition_variable cv_, idle_cv_;
  std::deque<Record> queue_, resend_;
  std::deque<std::pair<uint64_t, Record>> unacked_;  // (record number on this connection, record)
  std::unordered_map<std::string, uint32_t> ids_;    // name as given -> local id
  std::unordered_map<std::string, uint32_t> full_ids_;  // full name -> local id
  std::vector<Topic> topics_;                           // local id -> full name and type
  std::map<std::string, ValueType> declared_;
  Catalogue catalogue_;
  Stats stats_;
  std::string last_error_;
  std::set<std::pair<std::string, std::string>> reported_;
  std::vector<uint8_t> inbuf_;
  uint64_t conn_sent_ = 0, conn_archived_ = 0;
  bool stopping_ = false;
  bool in_flight_ = false;
  bool connected_ = false;
  size_t registered_ = 0;  // topics registered on the current connection
  int fd_ = -1;
  std::thread thread_;
};

}  // namespace modd
