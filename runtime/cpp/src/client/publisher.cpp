#include "modd/client/publisher.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace modd {

namespace {

// Framing of docs/ingress.md: varint length, type byte, body.
void put_varint(std::vector<uint8_t>& b, uint64_t v) {
  while (v >= 0x80) { b.push_back(static_cast<uint8_t>(v | 0x80)); v >>= 7; }
  b.push_back(static_cast<uint8_t>(v));
}
template <typename T>
void put_le(std::vector<uint8_t>& b, T v) {
  uint8_t x[sizeof(T)];
  std::memcpy(x, &v, sizeof(T));
  b.insert(b.end(), x, x + sizeof(T));
}
void put_string(std::vector<uint8_t>& b, const std::string& s) {
  put_varint(b, s.size());
  b.insert(b.end(), s.begin(), s.end());
}
void frame(std::vector<uint8_t>& out, uint8_t type, const std::vector<uint8_t>& body) {
  put_varint(out, body.size() + 1);
  out.push_back(type);
  out.insert(out.end(), body.begin(), body.end());
}

int open_socket(const std::string& ingress) {
  if (ingress.rfind("unix:", 0) == 0) {
    std::string path = ingress.substr(5);
    sockaddr_un a{};
    if (path.size() >= sizeof a.sun_path) return -1;
    int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) return -1;
    a.sun_family = AF_UNIX;
    std::memcpy(a.sun_path, path.c_str(), path.size() + 1);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) < 0) { ::close(fd); return -1; }
    return fd;
  }
  if (ingress.rfind("tcp:", 0) == 0) {
    std::string hp = ingress.substr(4);
    auto colon = hp.rfind(':');
    if (colon == std::string::npos) return -1;
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(std::atoi(hp.c_str() + colon + 1)));
    if (inet_pton(AF_INET, hp.substr(0, colon).c_str(), &a.sin_addr) != 1) return -1;
    int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) return -1;
    int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) < 0) { ::close(fd); return -1; }
    return fd;
  }
  return -1;
}

}  // namespace

Publisher::Publisher(std::string name, std::string ingress) : Publisher(std::move(name), std::move(ingress), Options{}) {}

Publisher::Publisher(std::string name, std::string ingress, Options options)
    : name_(std::move(name)), ingress_(std::move(ingress)), opt_(options) {
  thread_ = std::thread([this] { run(); });
}

Publisher::~Publisher() {
  flush(std::chrono::seconds(2));
  {
    std::lock_guard lk(mu_);
    stopping_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  disconnect();
}

void Publisher::declare(const std::string& topic, ValueType type) noexcept {
  try {
    std::lock_guard lk(mu_);
    if (ids_.count(topic)) return;
    ids_[topic] = static_cast<uint32_t>(topics_.size());
    topics_.push_back({topic, type});
  } catch (...) {
  }
}

bool Publisher::push(const std::string& topic, ValueType type, int64_t ts, double number, int64_t integer) noexcept {
  try {
    std::lock_guard lk(mu_);
    auto it = ids_.find(topic);
    if (it == ids_.end()) {
      it = ids_.emplace(topic, static_cast<uint32_t>(topics_.size())).first;
      topics_.push_back({topic, type});
    }
    const Topic& t = topics_[it->second];
    bool is_float = type == ValueType::Float32 || type == ValueType::Float64;
    bool t_float = t.type == ValueType::Float32 || t.type == ValueType::Float64;
    if (is_float != t_float && !(t.type == ValueType::Bool && type == ValueType::Int)) {
      ++stats_.dropped_bad_topic;
      return false;
    }
    if (queue_.size() >= opt_.queue_capacity) {
      ++stats_.dropped_queue_full;
      return false;
    }
    queue_.push_back({it->second, ts, number, integer});
    ++stats_.published;
  } catch (...) {
    return false;
  }
  cv_.notify_one();
  return true;
}

bool Publisher::publish(const std::string& topic, int64_t ts, float v) noexcept {
  return push(topic, ValueType::Float32, ts, v, 0);
}
bool Publisher::publish(const std::string& topic, int64_t ts, double v) noexcept {
  return push(topic, ValueType::Float64, ts, v, 0);
}
bool Publisher::publish(const std::string& topic, int64_t ts, int64_t v) noexcept {
  return push(topic, ValueType::Int, ts, 0, v);
}
bool Publisher::publish(const std::string& topic, int64_t ts, bool v) noexcept {
  return push(topic, ValueType::Bool, ts, 0, v ? 1 : 0);
}

bool Publisher::flush(std::chrono::milliseconds timeout) noexcept {
  std::unique_lock lk(mu_);
  cv_.notify_one();
  return idle_cv_.wait_for(lk, timeout, [&] { return queue_.empty() && !in_flight_; });
}

bool Publisher::connected() const noexcept {
  std::lock_guard lk(mu_);
  return connected_;
}

Publisher::Stats Publisher::stats() const noexcept {
  std::lock_guard lk(mu_);
  return stats_;
}

void Publisher::disconnect() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  std::lock_guard lk(mu_);
  connected_ = false;
}

bool Publisher::send_all(const std::vector<uint8_t>& b) {
  size_t done = 0;
  while (done < b.size()) {
    ssize_t n = ::send(fd_, b.data() + done, b.size() - done, MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    done += static_cast<size_t>(n);
  }
  return true;
}

bool Publisher::connect_and_register() {
  fd_ = open_socket(ingress_);
  if (fd_ < 0) return false;
  std::vector<uint8_t> out, body;
  body.push_back(1);  // ingress version
  put_string(body, name_);
  frame(out, 0x01, body);
  if (!send_all(out)) { disconnect(); return false; }
  std::lock_guard lk(mu_);
  connected_ = true;
  registered_ = 0;
  ++stats_.connects;
  return true;
}

void Publisher::run() {
  std::vector<Record> batch;
  std::vector<Topic> new_topics;
  for (;;) {
    size_t first_new = 0;
    {
      std::unique_lock lk(mu_);
      if (!batch.empty()) {
        // A batch that could not be sent is retried first, on the next connection.
      } else {
        cv_.wait(lk, [&] { return stopping_ || !queue_.empty(); });
        if (queue_.empty() && stopping_) break;
        while (!queue_.empty() && batch.size() < opt_.batch_max) {
          batch.push_back(queue_.front());
          queue_.pop_front();
        }
      }
      in_flight_ = true;
      if (stopping_ && fd_ < 0) {
        // Stopping with no broker: do not wait for one; what is left is counted.
        stats_.dropped_at_close += batch.size() + queue_.size();
        queue_.clear();
        in_flight_ = false;
        idle_cv_.notify_all();
        break;
      }
    }
    if (fd_ < 0 && !connect_and_register()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(opt_.reconnect_ms));
      continue;
    }
    std::vector<uint8_t> out;
    {
      std::lock_guard lk(mu_);
      first_new = registered_;
      new_topics.assign(topics_.begin() + static_cast<std::ptrdiff_t>(registered_), topics_.end());
    }
    for (size_t i = 0; i < new_topics.size(); ++i) {
      std::vector<uint8_t> body;
      put_varint(body, first_new + i);
      body.push_back(static_cast<uint8_t>(new_topics[i].type));
      put_string(body, new_topics[i].name);
      frame(out, 0x02, body);
    }
    std::vector<ValueType> types;
    {
      std::lock_guard lk(mu_);
      for (const auto& t : topics_) types.push_back(t.type);
    }
    std::vector<uint8_t> body;
    put_varint(body, batch.size());
    for (const Record& r : batch) {
      put_varint(body, r.id);
      put_le<int64_t>(body, r.ts);
      switch (types[r.id]) {
        case ValueType::Float32: put_le<float>(body, static_cast<float>(r.number)); break;
        case ValueType::Float64: put_le<double>(body, r.number); break;
        case ValueType::Int: put_le<int64_t>(body, r.integer); break;
        case ValueType::Bool: body.push_back(r.integer ? 1 : 0); break;
      }
    }
    frame(out, 0x03, body);
    if (!send_all(out)) {
      disconnect();
      continue;  // keep the batch; reconnect and send it again
    }
    std::lock_guard lk(mu_);
    registered_ = first_new + new_topics.size();
    stats_.sent += batch.size();
    batch.clear();
    in_flight_ = false;
    if (queue_.empty()) idle_cv_.notify_all();
  }
}

}  // namespace modd
