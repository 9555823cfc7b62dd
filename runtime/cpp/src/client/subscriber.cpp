#include "modd/client/subscriber.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace modd {
namespace {

constexpr size_t kMaxLine = 1 << 20;  // a longer line is malformed; the connection is dropped

// A JSON value of a delivered line: only what the payload uses.
struct Json {
  enum Kind { Null, Bool, Number, String, Array } kind = Null;
  double number = 0;
  bool boolean = false;
  std::string text;
  std::vector<Json> items;
};

// Minimal JSON reader for one flat object of the delivery payload. Unknown
// keys are skipped whatever their value; nesting is limited to arrays of scalars.
class Reader {
 public:
  explicit Reader(std::string_view s) : s_(s) {}

  bool object(std::vector<std::pair<std::string, Json>>& out, std::string& err) {
    ws();
    if (!eat('{')) return fail(err, "expected '{'");
    ws();
    if (eat('}')) return end(err);
    while (true) {
      std::string key;
      Json value;
      ws();
      if (!string(key)) return fail(err, "expected a key");
      ws();
      if (!eat(':')) return fail(err, "expected ':'");
      if (!this->value(value, 0)) return fail(err, "bad value of \"" + key + "\"");
      out.emplace_back(std::move(key), std::move(value));
      ws();
      if (eat('}')) return end(err);
      if (!eat(',')) return fail(err, "expected ',' or '}'");
    }
  }

 private:
  bool end(std::string& err) {
    ws();
    return pos_ == s_.size() || fail(err, "trailing characters");
  }
  bool fail(std::string& err, const std::string& what) {
    err = what + " at offset " + std::to_string(pos_);
    return false;
  }
  void ws() {
    while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\t' || s_[pos_] == '\r')) ++pos_;
  }
  bool eat(char c) {
    if (pos_ < s_.size() && s_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  bool literal(std::string_view word) {
    if (s_.substr(pos_, word.size()) != word) return false;
    pos_ += word.size();
    return true;
  }
  bool string(std::string& out) {
    if (!eat('"')) return false;
    while (pos_ < s_.size()) {
      char c = s_[pos_++];
      if (c == '"') return true;
      if (c != '\\') {
        out.push_back(c);
        continue;
      }
      if (pos_ >= s_.size()) return false;
      char e = s_[pos_++];
      switch (e) {
        case '"': case '\\': case '/': out.push_back(e); break;
        case 'b': out.push_back('\b'); break;
        case 'f': out.push_back('\f'); break;
        case 'n': out.push_back('\n'); break;
        case 'r': out.push_back('\r'); break;
        case 't': out.push_back('\t'); break;
        case 'u': {
          if (pos_ + 4 > s_.size()) return false;
          unsigned code = 0;
          for (int i = 0; i < 4; ++i) {
            char h = s_[pos_++];
            code <<= 4;
            if (h >= '0' && h <= '9') code |= unsigned(h - '0');
            else if (h >= 'a' && h <= 'f') code |= unsigned(h - 'a' + 10);
            else if (h >= 'A' && h <= 'F') code |= unsigned(h - 'A' + 10);
            else return false;
          }
          out.push_back(code < 0x80 ? char(code) : '?');  // names and units are ASCII
          break;
        }
        default: return false;
      }
    }
    return false;
  }
  bool number(double& out) {
    const char* begin = s_.data() + pos_;
    std::string buf(begin, std::min<size_t>(s_.size() - pos_, 64));
    char* end = nullptr;
    errno = 0;
    out = std::strtod(buf.c_str(), &end);
    if (end == buf.c_str() || errno == ERANGE) return false;
    pos_ += size_t(end - buf.c_str());
    return std::isfinite(out);
  }
  bool value(Json& v, int depth) {
    ws();
    if (pos_ >= s_.size()) return false;
    char c = s_[pos_];
    if (c == '"') {
      v.kind = Json::String;
      return string(v.text);
    }
    if (c == '[') {
      if (depth > 0) return false;
      ++pos_;
      v.kind = Json::Array;
      ws();
      if (eat(']')) return true;
      while (true) {
        Json item;
        if (!value(item, depth + 1)) return false;
        v.items.push_back(std::move(item));
        ws();
        if (eat(']')) return true;
        if (!eat(',')) return false;
      }
    }
    if (literal("null")) return true;
    if (literal("true")) {
      v.kind = Json::Bool;
      v.boolean = true;
      return true;
    }
    if (literal("false")) {
      v.kind = Json::Bool;
      return true;
    }
    v.kind = Json::Number;
    return number(v.number);
  }

  std::string_view s_;
  size_t pos_ = 0;
};

bool scalar(const Json& j, double& out) {
  if (j.kind == Json::Number) out = j.number;
  else if (j.kind == Json::Bool) out = j.boolean ? 1 : 0;
  else return false;
  return true;
}

bool integer(const Json& j, int64_t& out) {
  if (j.kind != Json::Number || j.number != std::floor(j.number)) return false;
  out = static_cast<int64_t>(j.number);
  return true;
}

}  // namespace

bool parse_delivered(std::string_view line, Delivered& out, std::string* error) {
  std::string err;
  std::vector<std::pair<std::string, Json>> fields;
  if (!Reader(line).object(fields, err)) {
    if (error) *error = err;
    return false;
  }
  out = Delivered{};
  int seen = 0;
  auto bad = [&](const std::string& key) {
    if (error) *error = "bad \"" + key + "\"";
    return false;
  };
  for (const auto& [key, v] : fields) {
    int64_t n = 0;
    if (key == "subscriber" || key == "topic" || key == "aggregation" || key == "period_s" ||
        key == "unit") {
      if (v.kind != Json::String) return bad(key);
      std::string* dst = key == "subscriber" ? &out.subscriber : key == "topic" ? &out.topic
                         : key == "aggregation" ? &out.aggregation : key == "period_s" ? &out.period_s
                         : &out.unit;
      *dst = v.text;
      ++seen;
    } else if (key == "config_id" || key == "slot") {
      if (!integer(v, n) || n < 0) return bad(key);
      (key == "slot" ? out.slot : out.config_id) = static_cast<uint64_t>(n);
    } else if (key == "start_ns" || key == "end_ns" || key == "delivered_ns") {
      if (!integer(v, n)) return bad(key);
      (key == "start_ns" ? out.start_ns : key == "end_ns" ? out.end_ns : out.delivered_ns) = n;
    } else if (key == "count") {
      if (v.kind != Json::Null && !integer(v, out.count)) return bad(key);
    } else if (key == "value") {
      if (v.kind == Json::Null) continue;
      out.present = true;
      if (v.kind == Json::Array) {
        for (const Json& item : v.items) {
          double d = 0;
          if (!scalar(item, d)) return bad(key);
          out.values.push_back(d);
        }
      } else if (!scalar(v, out.value)) {
        return bad(key);
      }
    } else if (key == "v") {
      if (!integer(v, n) || n > 1) return bad("v (unsupported payload version)");
    }
  }
  if (seen < 2 || out.topic.empty()) {
    if (error) *error = "not a delivered value (no topic)";
    return false;
  }
  return true;
}

Subscriber::Subscriber(const std::string& host, uint16_t port, Callback callback)
    : callback_(std::move(callback)) {
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  if (inet_pton(AF_INET, host.c_str(), &addr.sin_addr) != 1)
    throw std::runtime_error("modd::Subscriber: not an IPv4 address: " + host);
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  int one = 1;
  ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (listen_fd_ < 0 || ::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      ::listen(listen_fd_, 4) != 0) {
    std::string why = std::strerror(errno);
    if (listen_fd_ >= 0) ::close(listen_fd_);
    throw std::runtime_error("modd::Subscriber: cannot listen on " + host + ":" +
                             std::to_string(port) + ": " + why);
  }
  socklen_t len = sizeof addr;
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
  if (::pipe2(wake_, O_CLOEXEC | O_NONBLOCK) != 0) {
    ::close(listen_fd_);
    throw std::runtime_error("modd::Subscriber: pipe: " + std::string(std::strerror(errno)));
  }
}

Subscriber::~Subscriber() {
  stop();
  if (thread_.joinable()) thread_.join();
  for (int fd : {listen_fd_, wake_[0], wake_[1]})
    if (fd >= 0) ::close(fd);
}

void Subscriber::stop() noexcept {
  stopping_ = true;
  char b = 1;
  [[maybe_unused]] auto n = ::write(wake_[1], &b, 1);  // async-signal-safe
}

void Subscriber::start() { thread_ = std::thread([this] { run(); }); }

Subscriber::Stats Subscriber::stats() const noexcept {
  return Stats{received_.load(), malformed_.load(), connections_.load()};
}

void Subscriber::run() {
  while (!stopping_) {
    pollfd fds[2] = {{listen_fd_, POLLIN, 0}, {wake_[0], POLLIN, 0}};
    if (::poll(fds, 2, -1) < 0 && errno != EINTR) return;
    if (fds[1].revents) return;
    if (!(fds[0].revents & POLLIN)) continue;
    int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) continue;
    ++connections_;
    serve_connection(fd);  // the SubBroker holds one connection per subscriber
    ::close(fd);
  }
}

void Subscriber::serve_connection(int fd) {
  std::string buf;
  char chunk[4096];
  while (!stopping_) {
    pollfd fds[2] = {{fd, POLLIN, 0}, {wake_[0], POLLIN, 0}};
    if (::poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      return;
    }
    if (fds[1].revents) return;
    ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
    if (n <= 0) return;  // the SubBroker went away; it reconnects by itself
    buf.append(chunk, size_t(n));
    size_t start = 0, nl;
    while ((nl = buf.find('\n', start)) != std::string::npos) {
      std::string_view line(buf.data() + start, nl - start);
      start = nl + 1;
      if (line.empty()) continue;
      Delivered d;
      if (parse_delivered(line, d)) {
        ++received_;
        callback_(d);
      } else {
        ++malformed_;
      }
    }
    buf.erase(0, start);
    if (buf.size() > kMaxLine) {
      ++malformed_;
      return;
    }
  }
}

}  // namespace modd
