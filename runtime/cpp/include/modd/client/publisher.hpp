// MoDD publisher client: hands samples to the on-board PubBroker over its
// local ingress (docs/ingress.md). Self-contained (this header and
// publisher.cpp, standard library and POSIX only) so that an integrator can
// add it to their own CMake project.
//
//   modd::Publisher pub("pub_1", "unix:/run/modd/ingress.sock");
//   pub.declare("usv.accelerometer.accel_z", modd::ValueType::Float32);
//   pub.publish("usv.accelerometer.accel_z", now_ns(), 9.81f);
//
// publish() never blocks on the network and never throws: it appends to a
// bounded queue that a background thread sends in batches. When the queue is
// full (broker gone, link slow), the sample is dropped and counted in stats().
// The thread reconnects by itself and registers the topics again.
#pragma once
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
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
    size_t queue_capacity = 65536;  // samples waiting to be sent
    size_t batch_max = 256;         // records per SAMPLES frame
    int reconnect_ms = 200;         // wait between connection attempts
  };
  struct Stats {
    uint64_t published = 0;          // accepted into the queue
    uint64_t sent = 0;               // written to the broker's socket
    uint64_t dropped_queue_full = 0;
    uint64_t dropped_bad_topic = 0;  // type clash with the topic's declared type
    uint64_t dropped_at_close = 0;   // still queued when the publisher was destroyed with no broker
    uint64_t connects = 0;
  };

  // ingress: "unix:/path/to/socket" or "tcp:127.0.0.1:7373".
  Publisher(std::string name, std::string ingress);
  Publisher(std::string name, std::string ingress, Options options);
  ~Publisher();  // sends what is queued (up to 2 s), then disconnects
  Publisher(const Publisher&) = delete;
  Publisher& operator=(const Publisher&) = delete;

  // Declares a topic's type; without it, the first publish() decides.
  void declare(const std::string& topic, ValueType type) noexcept;
  bool publish(const std::string& topic, int64_t timestamp_ns, float value) noexcept;
  bool publish(const std::string& topic, int64_t timestamp_ns, double value) noexcept;
  bool publish(const std::string& topic, int64_t timestamp_ns, int64_t value) noexcept;
  bool publish(const std::string& topic, int64_t timestamp_ns, bool value) noexcept;
  // Any other integer type (int, long long, uint8_t, ...) publishes as an int topic.
  template <typename T>
    requires(std::is_integral_v<T> && !std::is_same_v<T, bool> && !std::is_same_v<T, int64_t>)
  bool publish(const std::string& topic, int64_t timestamp_ns, T value) noexcept {
    return publish(topic, timestamp_ns, static_cast<int64_t>(value));
  }
  // Waits until the queue is empty and written (true) or the timeout passes.
  bool flush(std::chrono::milliseconds timeout) noexcept;
  bool connected() const noexcept;
  Stats stats() const noexcept;

 private:
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
  bool push(const std::string& topic, ValueType type, int64_t ts, double number, int64_t integer) noexcept;
  void run();
  bool connect_and_register();
  bool send_all(const std::vector<uint8_t>& bytes);
  void disconnect();

  std::string name_, ingress_;
  Options opt_;
  mutable std::mutex mu_;
  std::condition_variable cv_, idle_cv_;
  std::deque<Record> queue_;
  std::unordered_map<std::string, uint32_t> ids_;
  std::vector<Topic> topics_;
  Stats stats_;
  bool stopping_ = false;
  bool in_flight_ = false;
  bool connected_ = false;
  size_t registered_ = 0;  // topics registered on the current connection
  int fd_ = -1;
  std::thread thread_;
};

}  // namespace modd
