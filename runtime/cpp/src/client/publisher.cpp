#include "modd/client/publisher.hpp"
#include "modd/ingress/wire.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>

namespace modd {

namespace {

// The wire, as the broker writes and reads it (modd/ingress/wire.hpp, carried with the client).
using ingress::kMaxFrame;
using ingress::kVersion;
using ingress::MsgType;
using ingress::wire::put_fixed;
using ingress::wire::put_frame;
using ingress::wire::put_string;
using ingress::wire::put_varint;
const char* const kReasons[] = {"unknown topic",
                                "wrong type",
                                "value not finite",
                                "timestamp out of bounds",
                                "archive queue full",
                                "malformed",
                                "over its fair share of the archive queue"};

// Bounds-checked reader of a reply body; `ok` turns false on a short or bad field.
struct Reader {
  const uint8_t* p;
  size_t n, at = 0;
  bool ok = true;
  uint64_t varint() {
    uint64_t v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      if (at >= n) break;
      uint8_t b = p[at++];
      v |= static_cast<uint64_t>(b & 0x7f) << shift;
      if (!(b & 0x80)) return v;
    }
    ok = false;
    return 0;
  }
  uint8_t u8() {
    if (at >= n) {
      ok = false;
      return 0;
    }
    return p[at++];
  }
  std::string string() {
    uint64_t len = varint();
    if (!ok || len > n - at) {
      ok = false;
      return {};
    }
    std::string s(reinterpret_cast<const char*>(p + at), len);
    at += len;
    return s;
  }
};

int open_socket(const std::string& ingress) {
  if (ingress.rfind("unix:", 0) == 0) {
    std::string path = ingress.substr(5);
    sockaddr_un a{};
    if (path.size() >= sizeof a.sun_path) return -1;
    int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) return -1;
    a.sun_family = AF_UNIX;
    std::memcpy(a.sun_path, path.c_str(), path.size() + 1);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) < 0) {
      ::close(fd);
      return -1;
    }
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
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) < 0) {
      ::close(fd);
      return -1;
    }
    return fd;
  }
  return -1;
}

int64_t realtime_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

const char* type_name(ValueType t) {
  switch (t) {
    case ValueType::Float32: return "float32";
    case ValueType::Float64: return "float64";
    case ValueType::Int: return "int";
    case ValueType::Bool: return "bool";
  }
  return "?";
}

}  // namespace

Publisher::Publisher(std::string name, std::string ingress)
    : Publisher(std::move(name), std::move(ingress), Options{}) {}

Publisher::Publisher(std::string name, std::string ingress, Options options)
    : name_(std::move(name)), ingress_(std::move(ingress)), opt_(std::move(options)) {
  thread_ = std::thread([this] { run(); });
  std::unique_lock lk(mu_);
  idle_cv_.wait_for(lk, std::chrono::milliseconds(opt_.connect_wait_ms),
                    [&] { return catalogue_.known; });
}

Publisher::~Publisher() {
  auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  flush(std::chrono::seconds(2));
  bool v2;
  {
    std::lock_guard lk(mu_);
    v2 = catalogue_.known;
  }
  if (v2)
    wait_on_disk(std::chrono::duration_cast<std::chrono::milliseconds>(
        until - std::chrono::steady_clock::now()));
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
    declared_[topic] = type;
  } catch (...) {}
}

void Publisher::report(const std::string& topic, const std::string& why) {
  if (!reported_.insert({topic, why.substr(0, why.find(':'))}).second) return;
  if (opt_.on_error)
    opt_.on_error(topic, why);
  else
    std::fprintf(stderr, "modd::Publisher %s: %s\n", name_.c_str(), why.c_str());
}

bool Publisher::refuse(const std::string& topic, uint64_t Stats::*counter, const std::string& why) {
  ++(stats_.*counter);
  ++stats_.dropped_bad_topic;
  last_error_ = why;
  report(topic, why);
  return false;
}

bool Publisher::resolve(const std::string& given, std::string& full, std::string& why) const {
  if (catalogue_.topics.count(given)) {
    full = given;
    return true;
  }
  std::vector<std::string> hits;
  for (const auto& [name, type] : catalogue_.topics)
    if (name.size() > given.size() &&
        name.compare(name.size() - given.size(), given.size(), given) == 0 &&
        name[name.size() - given.size() - 1] == '.')
      hits.push_back(name);
  if (hits.size() == 1) {
    full = hits[0];
    return true;
  }
  if (hits.empty() && catalogue_.accept_unknown) {
    full = given;
    return true;
  }
  std::string list;
  const auto& names = hits.empty() ? std::vector<std::string>() : hits;
  if (hits.empty())
    for (const auto& [name, type] : catalogue_.topics) list += (list.empty() ? "" : ", ") + name;
  else
    for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  why = hits.empty() ? "unknown topic '" + given + "': drone '" + catalogue_.drone +
                           "' publishes " + (list.empty() ? std::string("no topic") : list)
                     : "ambiguous topic '" + given + "': matches " + list + " (use the full name)";
  return false;
}

bool Publisher::push(const std::string& topic, int64_t ts, In v) noexcept {
  try {
    std::lock_guard lk(mu_);
    uint32_t id;
    auto it = ids_.find(topic);
    if (it != ids_.end()) {
      id = it->second;
    } else {
      std::string full = topic, why;
      if (catalogue_.known && !resolve(topic, full, why))
        return refuse(topic, &Stats::refused_unknown_topic, why);
      ValueType type;
      auto cat = catalogue_.topics.find(full);
      auto dec = declared_.find(full);
      if (dec == declared_.end()) dec = declared_.find(topic);
      if (cat != catalogue_.topics.end()) {
        type = cat->second;
        if (dec != declared_.end() && dec->second != type)
          return refuse(topic, &Stats::refused_wrong_type,
                        "wrong type: topic '" + full + "' is " + type_name(type) + " on drone '" +
                            catalogue_.drone + "', declared " + type_name(dec->second));
      } else if (dec != declared_.end()) {
        type = dec->second;
      } else {
        type = v.kind == In::Float32   ? ValueType::Float32
               : v.kind == In::Float64 ? ValueType::Float64
               : v.kind == In::Bool    ? ValueType::Bool
                                       : ValueType::Int;
      }
      auto f = full_ids_.find(full);
      if (f == full_ids_.end()) {
        f = full_ids_.emplace(full, static_cast<uint32_t>(topics_.size())).first;
        topics_.push_back({full, type});
      }
      id = f->second;
      ids_.emplace(topic, id);
    }
    const Topic& t = topics_[id];
    // The value, converted to the declared type (rules in publisher.hpp and docs/ingress.md).
    double number = 0;
    int64_t integer = 0;
    double x = v.kind == In::Signed     ? static_cast<double>(v.i)
               : v.kind == In::Unsigned ? static_cast<double>(v.u)
               : v.kind == In::Bool     ? static_cast<double>(v.i)
                                        : v.d;
    auto out_of_range = [&](const char* what) {
      return refuse(topic, &Stats::refused_out_of_range,
                    std::string("value out of range: ") + what + " for topic '" + t.name + "' (" +
                        type_name(t.type) + ")");
    };
    switch (t.type) {
      case ValueType::Float32:
        if (!std::isfinite(x)) return out_of_range("NaN or infinite");
        if (std::fabs(x) > FLT_MAX) return out_of_range("beyond ±FLT_MAX");
        number = static_cast<float>(x);
        break;
      case ValueType::Float64:
        if (!std::isfinite(x)) return out_of_range("NaN or infinite");
        number = x;
        break;
      case ValueType::Int:
        if (v.kind == In::Signed || v.kind == In::Bool) {
          integer = v.i;
        } else if (v.kind == In::Unsigned) {
          if (v.u > static_cast<uint64_t>(INT64_MAX)) return out_of_range("above INT64_MAX");
          integer = static_cast<int64_t>(v.u);
        } else {
          if (!std::isfinite(x)) return out_of_range("NaN or infinite");
          double r = std::round(x);
          if (r < -9223372036854775808.0 || r >= 9223372036854775808.0)
            return out_of_range("beyond int64");
          integer = static_cast<int64_t>(r);
        }
        break;
      case ValueType::Bool:
        if (x != 0 && x != 1) return out_of_range("a bool takes 0 or 1");
        integer = x == 1 ? 1 : 0;
        break;
    }
    if (catalogue_.known && (catalogue_.max_future_ms || catalogue_.max_past_ms)) {
      __int128 ahead = static_cast<__int128>(ts) - realtime_ns();
      if ((catalogue_.max_future_ms &&
           ahead > static_cast<__int128>(catalogue_.max_future_ms) * 1'000'000) ||
          (catalogue_.max_past_ms &&
           -ahead > static_cast<__int128>(catalogue_.max_past_ms) * 1'000'000)) {
        char buf[200];
        std::snprintf(
            buf, sizeof buf,
            "timestamp out of bounds: %lld ns is %.3g s %s this clock (bounds %llu ms ahead, "
            "%llu ms behind)",
            static_cast<long long>(ts), std::fabs(static_cast<double>(ahead)) / 1e9,
            ahead > 0 ? "ahead of" : "behind",
            static_cast<unsigned long long>(catalogue_.max_future_ms),
            static_cast<unsigned long long>(catalogue_.max_past_ms));
        return refuse(topic, &Stats::refused_timestamp, "topic '" + t.name + "': " + buf);
      }
    }
    if (queue_.size() >= opt_.queue_capacity) {
      ++stats_.dropped_queue_full;
      return false;
    }
    queue_.push_back({id, ts, number, integer});
    ++stats_.published;
  } catch (...) { return false; }
  cv_.notify_one();
  return true;
}

bool Publisher::publish(const std::string& topic, int64_t ts, float v) noexcept {
  return push(topic, ts, In{In::Float32, v, 0, 0});
}
bool Publisher::publish(const std::string& topic, int64_t ts, double v) noexcept {
  return push(topic, ts, In{In::Float64, v, 0, 0});
}
bool Publisher::publish(const std::string& topic, int64_t ts, int64_t v) noexcept {
  return push(topic, ts, In{In::Signed, 0, v, 0});
}
bool Publisher::publish(const std::string& topic, int64_t ts, bool v) noexcept {
  return push(topic, ts, In{In::Bool, 0, v ? 1 : 0, 0});
}

bool Publisher::flush(std::chrono::milliseconds timeout) noexcept {
  std::unique_lock lk(mu_);
  cv_.notify_one();
  return idle_cv_.wait_for(lk, timeout,
                           [&] { return queue_.empty() && resend_.empty() && !in_flight_; });
}

bool Publisher::wait_on_disk(std::chrono::milliseconds timeout) noexcept {
  std::unique_lock lk(mu_);
  cv_.notify_one();
  return idle_cv_.wait_for(lk, timeout, [&] {
    return queue_.empty() && resend_.empty() && !in_flight_ && unacked_.empty();
  });
}

bool Publisher::connected() const noexcept {
  std::lock_guard lk(mu_);
  return connected_;
}

Publisher::Stats Publisher::stats() const noexcept {
  std::lock_guard lk(mu_);
  return stats_;
}

std::string Publisher::last_error() const noexcept {
  try {
    std::lock_guard lk(mu_);
    return last_error_;
  } catch (...) { return {}; }
}

void Publisher::disconnect() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  std::lock_guard lk(mu_);
  connected_ = false;
  inbuf_.clear();
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

bool Publisher::connect_and_hello() {
  fd_ = open_socket(ingress_);
  if (fd_ < 0) return false;
  std::vector<uint8_t> out, body;
  body.push_back(kVersion);
  put_string(body, name_);
  put_frame(out, MsgType::Hello, body);
  if (!send_all(out)) {
    disconnect();
    return false;
  }
  std::lock_guard lk(mu_);
  connected_ = true;
  registered_ = 0;
  conn_sent_ = 0;
  conn_archived_ = 0;
  ++stats_.connects;
  // What was sent but is not known on disk goes again, first (a broker restart loses the
  // samples of its buffers that were not yet written).
  stats_.replayed += unacked_.size();
  for (auto it = unacked_.rbegin(); it != unacked_.rend(); ++it) resend_.push_front(it->second);
  unacked_.clear();
  return true;
}

void Publisher::handle_reply(uint8_t type, const uint8_t* p, size_t n) {
  Reader r{p, n};
  std::lock_guard lk(mu_);
  if (type == static_cast<uint8_t>(MsgType::Catalogue)) {
    Catalogue c;
    c.drone = r.string();
    c.max_future_ms = r.varint();
    c.max_past_ms = r.varint();
    c.accept_unknown = r.u8() == 1;
    uint64_t count = r.varint();
    for (uint64_t i = 0; r.ok && i < count; ++i) {
      uint8_t t = r.u8();
      std::string name = r.string();
      if (t <= 3) c.topics[name] = static_cast<ValueType>(t);
    }
    if (!r.ok) return;
    c.known = true;
    catalogue_ = std::move(c);
    idle_cv_.notify_all();
  } else if (type == static_cast<uint8_t>(MsgType::Ack)) {
    uint64_t received = r.varint(), settled = r.varint(), archived = r.varint();
    if (!r.ok) return;
    (void)received;
    while (!unacked_.empty() && unacked_.front().first < settled) unacked_.pop_front();
    if (archived > conn_archived_) stats_.on_disk += archived - conn_archived_;
    conn_archived_ = std::max(conn_archived_, archived);
    idle_cv_.notify_all();
  } else if (type == static_cast<uint8_t>(MsgType::Reject)) {
    uint64_t id = r.varint();
    uint8_t reason = r.u8();
    uint64_t count = r.varint();
    std::string detail = r.string();
    if (!r.ok) return;
    stats_.rejected_by_broker += count;
    std::string topic = id < topics_.size() ? topics_[id].name : "?";
    std::string why =
        std::string("refused by the broker (") +
        (reason < sizeof kReasons / sizeof *kReasons ? kReasons[reason] : "unknown reason") +
        "): " + detail;
    last_error_ = why;
    report(topic, "broker " + std::to_string(reason) + ": " + why);
  }
}

void Publisher::read_replies() {
  uint8_t buf[4096];
  for (;;) {
    ssize_t n = ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT);
    if (n == 0) {
      disconnect();
      return;
    }
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK) disconnect();
      break;
    }
    inbuf_.insert(inbuf_.end(), buf, buf + n);
  }
  size_t at = 0;
  while (at < inbuf_.size()) {
    Reader r{inbuf_.data() + at, inbuf_.size() - at};
    uint64_t len = r.varint();
    if (!r.ok) break;  // length not complete yet
    if (len == 0 || len > kMaxFrame) {
      disconnect();
      return;
    }
    if (r.n - r.at < len) break;
    handle_reply(inbuf_[at + r.at], inbuf_.data() + at + r.at + 1, len - 1);
    at += r.at + len;
  }
  inbuf_.erase(inbuf_.begin(), inbuf_.begin() + static_cast<std::ptrdiff_t>(at));
}

void Publisher::run() {
  using clock = std::chrono::steady_clock;
  auto next_attempt = clock::now();  // the first attempt, and the first after a loss, at once
  std::vector<Record> batch;
  std::vector<Topic> new_topics;
  for (;;) {
    {
      std::unique_lock lk(mu_);
      cv_.wait_for(lk, std::chrono::milliseconds(20), [&] {
        return stopping_ || ((!queue_.empty() || !resend_.empty()) && !in_flight_ && fd_ >= 0);
      });
      if (stopping_ && (fd_ < 0 || (queue_.empty() && resend_.empty()))) {
        if (fd_ < 0) stats_.dropped_at_close += queue_.size() + resend_.size();
        queue_.clear();
        resend_.clear();
        idle_cv_.notify_all();
        break;
      }
    }
    if (fd_ < 0) {
      if (clock::now() < next_attempt) continue;
      if (!connect_and_hello()) {
        next_attempt = clock::now() + std::chrono::milliseconds(opt_.reconnect_ms);
        continue;
      }
    }
    read_replies();
    if (fd_ < 0) {
      next_attempt = clock::now();
      continue;
    }
    size_t first_new = 0;
    std::vector<ValueType> types;
    {
      std::lock_guard lk(mu_);
      while (!resend_.empty() && batch.size() < opt_.batch_max) {
        batch.push_back(resend_.front());
        resend_.pop_front();
      }
      while (!queue_.empty() && batch.size() < opt_.batch_max) {
        batch.push_back(queue_.front());
        queue_.pop_front();
      }
      if (batch.empty()) {
        in_flight_ = false;
        idle_cv_.notify_all();
        continue;
      }
      in_flight_ = true;
      first_new = registered_;
      new_topics.assign(topics_.begin() + static_cast<std::ptrdiff_t>(registered_), topics_.end());
      for (const auto& t : topics_) types.push_back(t.type);
    }
    std::vector<uint8_t> out;
    for (size_t i = 0; i < new_topics.size(); ++i) {
      std::vector<uint8_t> body;
      put_varint(body, first_new + i);
      body.push_back(static_cast<uint8_t>(new_topics[i].type));
      put_string(body, new_topics[i].name);
      put_frame(out, MsgType::Register, body);
    }
    std::vector<uint8_t> body;
    put_varint(body, batch.size());
    for (const Record& r : batch) {
      put_varint(body, r.id);
      put_fixed<int64_t>(body, r.ts);
      switch (types[r.id]) {
        case ValueType::Float32: put_fixed<float>(body, static_cast<float>(r.number)); break;
        case ValueType::Float64: put_fixed<double>(body, r.number); break;
        case ValueType::Int: put_fixed<int64_t>(body, r.integer); break;
        case ValueType::Bool: body.push_back(r.integer ? 1 : 0); break;
      }
    }
    put_frame(out, MsgType::Samples, body);
    if (!send_all(out)) {
      disconnect();
      std::lock_guard lk(mu_);
      for (auto it = batch.rbegin(); it != batch.rend(); ++it)
        resend_.push_front(*it);  // sent again, first
      batch.clear();
      in_flight_ = false;
      next_attempt = clock::now();
      continue;
    }
    std::lock_guard lk(mu_);
    registered_ = first_new + new_topics.size();
    stats_.sent += batch.size();
    for (const Record& r : batch) {
      if (unacked_.size() >= opt_.replay_capacity) {
        unacked_.pop_front();
        ++stats_.replay_dropped;
      }
      unacked_.emplace_back(conn_sent_++, r);
    }
    batch.clear();
    in_flight_ = false;
    if (queue_.empty() && resend_.empty()) idle_cv_.notify_all();
  }
}

}  // namespace modd
