#include "modd/client/subscriber.hpp"

#include "modd/client/delivered_value.gen.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/random.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <iterator>
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
        case '"':
        case '\\':
        case '/': out.push_back(e); break;
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
            if (h >= '0' && h <= '9')
              code |= unsigned(h - '0');
            else if (h >= 'a' && h <= 'f')
              code |= unsigned(h - 'a' + 10);
            else if (h >= 'A' && h <= 'F')
              code |= unsigned(h - 'A' + 10);
            else
              return false;
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
    size_t start = pos_;
    if (!number(v.number)) return false;
    v.text.assign(s_.substr(start, pos_ - start));  // the literal: integers are read exactly
    return true;
  }

  std::string_view s_;
  size_t pos_ = 0;
};

bool scalar(const Json& j, double& out) {
  if (j.kind == Json::Number)
    out = j.number;
  else if (j.kind == Json::Bool)
    out = j.boolean ? 1 : 0;
  else
    return false;
  return true;
}

bool integer(const Json& j, int64_t& out) {
  if (j.kind != Json::Number || j.number != std::floor(j.number)) return false;
  // Nanosecond times exceed a double's 53 bits: read an integer literal exactly.
  if (!j.text.empty() && j.text.find_first_of(".eE") == std::string::npos) {
    errno = 0;
    char* end = nullptr;
    long long n = std::strtoll(j.text.c_str(), &end, 10);
    if (errno == ERANGE || end != j.text.c_str() + j.text.size()) return false;
    out = static_cast<int64_t>(n);
    return true;
  }
  // Range first: casting a double outside int64_t's range is undefined behaviour.
  if (!(j.number >= -9223372036854775808.0 && j.number < 9223372036854775808.0)) return false;
  out = static_cast<int64_t>(j.number);
  return true;
}

// ---- SHA-256 (FIPS 180-4) and HMAC (RFC 2104): the client carries its own, so
// that a scientist's project builds with a compiler and CMake only. ----------
constexpr uint32_t kK[64] = {
    0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
    0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
    0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
    0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
    0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
    0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
    0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
    0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};

uint32_t rotr(uint32_t x, int n) { return (x >> n) | (x << (32 - n)); }

void sha256_block(uint32_t h[8], const uint8_t* p) {
  uint32_t w[64];
  for (int i = 0; i < 16; ++i)
    w[i] = uint32_t(p[4 * i]) << 24 | uint32_t(p[4 * i + 1]) << 16 | uint32_t(p[4 * i + 2]) << 8 |
           uint32_t(p[4 * i + 3]);
  for (int i = 16; i < 64; ++i) {
    uint32_t s0 = rotr(w[i - 15], 7) ^ rotr(w[i - 15], 18) ^ (w[i - 15] >> 3);
    uint32_t s1 = rotr(w[i - 2], 17) ^ rotr(w[i - 2], 19) ^ (w[i - 2] >> 10);
    w[i] = w[i - 16] + s0 + w[i - 7] + s1;
  }
  uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], k = h[7];
  for (int i = 0; i < 64; ++i) {
    uint32_t t1 =
        k + (rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25)) + ((e & f) ^ (~e & g)) + kK[i] + w[i];
    uint32_t t2 = (rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
    k = g;
    g = f;
    f = e;
    e = d + t1;
    d = c;
    c = b;
    b = a;
    a = t1 + t2;
  }
  h[0] += a;
  h[1] += b;
  h[2] += c;
  h[3] += d;
  h[4] += e;
  h[5] += f;
  h[6] += g;
  h[7] += k;
}

std::string hex(const uint8_t* p, size_t n) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  for (size_t i = 0; i < n; ++i) {
    out.push_back(digits[p[i] >> 4]);
    out.push_back(digits[p[i] & 15]);
  }
  return out;
}

bool equal_ct(std::string_view a, std::string_view b) {  // constant time for equal lengths
  if (a.size() != b.size()) return false;
  unsigned diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= unsigned(uint8_t(a[i]) ^ uint8_t(b[i]));
  return diff == 0;
}

constexpr std::string_view kGreeting = "MODD-DELIVERY/1 ";
constexpr std::string_view kProofLabel = "modd-delivery/1\n";
constexpr size_t kMaxKeyFile = 4096;

std::string read_key_file(const std::string& path) {
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) throw std::runtime_error("delivery key file:" + path + ": " + std::strerror(errno));
  struct stat st {};
  std::string data;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || st.st_size > off_t(kMaxKeyFile)) {
    ::close(fd);
    throw std::runtime_error("delivery key file:" + path + ": not a regular file of at most 4 KiB");
  }
  char buf[kMaxKeyFile + 1];
  ssize_t n = ::read(fd, buf, sizeof buf);
  ::close(fd);
  if (n < 0 || size_t(n) > kMaxKeyFile)
    throw std::runtime_error("delivery key file:" + path + ": unreadable");
  data.assign(buf, size_t(n));
  if (!data.empty() && data.back() == '\n') data.pop_back();
  if (data.empty()) throw std::runtime_error("delivery key file:" + path + ": empty");
  return data;
}

std::string default_key_path() {
  const char* xdg = std::getenv("XDG_CONFIG_HOME");
  const char* home = std::getenv("HOME");
  std::string dir = xdg && *xdg ? std::string(xdg) : std::string(home ? home : "") + "/.config";
  return dir + "/modd/delivery.key";
}

// Creates the key file when absent, atomically (a temporary file linked into
// place, so that a SubBroker and a subscriber starting together agree).
void create_key_file(const std::string& path) {
  std::string dir = path.substr(0, path.rfind('/'));
  std::string parent = dir.substr(0, dir.rfind('/'));
  ::mkdir(parent.c_str(), 0700);
  ::mkdir(dir.c_str(), 0700);
  uint8_t raw[32];
  if (::getrandom(raw, sizeof raw, 0) != ssize_t(sizeof raw))
    throw std::runtime_error("getrandom failed");
  std::string key = hex(raw, sizeof raw) + "\n";
  std::string tmp = path + ".tmp" + std::to_string(::getpid());
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (fd < 0) return;  // another process is writing it; reading decides
  bool ok = ::write(fd, key.data(), key.size()) == ssize_t(key.size());
  ::close(fd);
  if (ok && ::link(tmp.c_str(), path.c_str()) != 0) {
    // EEXIST: another process put its key there first; that one is used.
  }
  ::unlink(tmp.c_str());
}

}  // namespace

Digest sha256(std::string_view data) {
  uint32_t h[8] = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                   0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
  size_t full = data.size() / 64;
  for (size_t i = 0; i < full; ++i)
    sha256_block(h, reinterpret_cast<const uint8_t*>(data.data()) + 64 * i);
  uint8_t tail[128] = {};
  size_t rest = data.size() - 64 * full;
  std::memcpy(tail, data.data() + 64 * full, rest);
  tail[rest] = 0x80;
  size_t blocks = rest + 9 > 64 ? 2 : 1;
  uint64_t bits = uint64_t(data.size()) * 8;
  for (int i = 0; i < 8; ++i) tail[64 * blocks - 1 - i] = uint8_t(bits >> (8 * i));
  for (size_t i = 0; i < blocks; ++i) sha256_block(h, tail + 64 * i);
  Digest out{};
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 4; ++j) out[4 * i + j] = uint8_t(h[i] >> (24 - 8 * j));
  return out;
}

Digest hmac_sha256(std::string_view key, std::string_view data) {
  std::string k(key);
  if (k.size() > 64) {
    Digest d = sha256(k);
    k.assign(reinterpret_cast<const char*>(d.data()), d.size());
  }
  k.resize(64, '\0');
  std::string inner(64, '\0'), outer(64, '\0');
  for (int i = 0; i < 64; ++i) {
    inner[i] = char(k[i] ^ 0x36);
    outer[i] = char(k[i] ^ 0x5c);
  }
  Digest ih = sha256(inner + std::string(data));
  return sha256(outer + std::string(reinterpret_cast<const char*>(ih.data()), ih.size()));
}

std::string delivery_proof(std::string_view key, std::string_view nonce_hex) {
  Digest d = hmac_sha256(key, std::string(kProofLabel) + std::string(nonce_hex));
  return hex(d.data(), d.size());
}

std::string load_delivery_key() {
  const char* ref = std::getenv("MODD_DELIVERY_KEY");
  if (ref && *ref) {
    std::string r(ref);
    if (r.rfind("env:", 0) == 0) {
      const char* v = std::getenv(r.c_str() + 4);
      if (!v || !*v) throw std::runtime_error("delivery key " + r + ": the variable is not set");
      return v;
    }
    if (r.rfind("file:", 0) == 0) return read_key_file(r.substr(5));
    throw std::runtime_error("MODD_DELIVERY_KEY: expected env:NAME or file:PATH");
  }
  std::string path = default_key_path();
  if (::access(path.c_str(), F_OK) != 0) create_key_file(path);
  return read_key_file(path);
}

bool parse_delivered(std::string_view line, Delivered& out, std::string* error) {
  std::string err;
  std::vector<std::pair<std::string, Json>> fields;
  if (!Reader(line).object(fields, err)) {
    if (error) *error = err;
    return false;
  }
  out = Delivered{};
  int seen = 0, identity = 0;
  auto bad = [&](const std::string& key) {
    if (error) *error = "bad \"" + key + "\"";
    return false;
  };
  namespace f = delivered_value;
  for (const auto& [key, v] : fields) {
    int64_t n = 0;
    if (key == f::kSubscriber || key == f::kTopic || key == f::kAggregation || key == f::kPeriodS ||
        key == f::kUnit) {
      if (v.kind != Json::String) return bad(key);
      std::string* dst = key == f::kSubscriber    ? &out.subscriber
                         : key == f::kTopic       ? &out.topic
                         : key == f::kAggregation ? &out.aggregation
                         : key == f::kPeriodS     ? &out.period_s
                                                  : &out.unit;
      *dst = v.text;
      ++seen;
    } else if (key == f::kConfigId || key == f::kSlot) {
      if (!integer(v, n) || n < 0) return bad(key);
      (key == f::kSlot ? out.slot : out.config_id) = static_cast<uint64_t>(n);
    } else if (key == f::kStartNs || key == f::kEndNs || key == f::kDeliveredNs) {
      if (!integer(v, n)) return bad(key);
      (key == f::kStartNs ? out.start_ns : key == f::kEndNs ? out.end_ns : out.delivered_ns) = n;
    } else if (key == f::kCount) {
      if (v.kind != Json::Null && !integer(v, out.count)) return bad(key);
    } else if (key == f::kValue) {
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
    } else if (key == f::kBackfilled) {
      if (v.kind != Json::Bool) return bad(key);
      out.backfilled = v.boolean;
    } else if (key == f::kDrone) {
      if (v.kind == Json::Null) continue;
      if (v.kind != Json::String) return bad(key);
      out.drone = v.text;
      identity |= 1;
    } else if (key == f::kEpochNs || key == f::kWindow) {
      if (v.kind == Json::Null) continue;
      if (!integer(v, n)) return bad(key);
      (key == f::kEpochNs ? out.epoch_ns : out.window) = n;
      identity |= key == f::kEpochNs ? 2 : 4;
    } else if (key == f::kV) {
      if (!integer(v, n) || n > f::kVersion) {
        return bad(std::string(f::kV) + " (unsupported payload version)");
      }
    }
  }
  if (seen < 2 || out.topic.empty()) {
    if (error) *error = "not a delivered value (no topic)";
    return false;
  }
  out.has_identity = identity == 7;
  return true;
}

SeenWindows::SeenWindows(size_t max_runs, size_t max_keys)
    : max_runs_(std::max<size_t>(max_runs, 1)), max_keys_(std::max<size_t>(max_keys, 1)) {}

bool SeenWindows::first(const Delivered& d) {
  return !d.has_identity || first(d.drone, d.subscriber, d.period_s, d.epoch_ns, d.window);
}

SeenWindows::Runs& SeenWindows::runs_of(Key key) {
  auto [at, added] = keys_.try_emplace(std::move(key));
  at->second.used = ++tick_;
  if (added && keys_.size() > max_keys_) {  // forget the least recently heard key
    auto oldest = std::min_element(keys_.begin(), keys_.end(), [](const auto& a, const auto& b) {
      return a.second.used < b.second.used;
    });
    keys_.erase(oldest);
  }
  return at->second;
}

bool SeenWindows::first(const std::string& drone, const std::string& subscriber,
                        const std::string& period_s, int64_t epoch_ns, int64_t window) {
  auto& last = runs_of({drone, subscriber, period_s}).last;
  auto after = last.upper_bound({epoch_ns, window});  // the first run starting past it
  int64_t lo = window, hi = window;
  if (after != last.begin()) {
    auto before = std::prev(after);
    if (before->first.first == epoch_ns) {
      if (window <= before->second) return false;  // inside a run: had
      if (before->second == window - 1) {          // window > before's last: no overflow
        lo = before->first.second;
        last.erase(before);
      }
    }
  }
  if (after != last.end() && after->first.first == epoch_ns && window < INT64_MAX &&
      after->first.second == window + 1) {
    hi = after->second;
    last.erase(after);
  }
  last.emplace(std::make_pair(epoch_ns, lo), hi);
  if (last.size() > max_runs_) last.erase(last.begin());  // the oldest run
  return true;
}

Subscriber::Subscriber(const std::string& host, uint16_t port, Callback callback)
    : Subscriber(host, port, std::move(callback), Options{}) {}

Subscriber::Subscriber(const std::string& host, uint16_t port, Callback callback, Options options)
    : callback_(std::move(callback)), options_(std::move(options)) {
  if (options_.key.empty()) options_.key = load_delivery_key();
  if (options_.max_connections == 0) options_.max_connections = 1;
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  if (inet_pton(AF_INET, host.c_str(), &addr.sin_addr) != 1)
    throw std::runtime_error("modd::Subscriber: not an IPv4 address: " + host);
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  int one = 1;
  ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (listen_fd_ < 0 || ::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      ::listen(listen_fd_, 16) != 0) {
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

void Subscriber::start() {
  thread_ = std::thread([this] { run(); });
}

Subscriber::Stats Subscriber::stats() const noexcept {
  return Stats{received_.load(), malformed_.load(), connections_.load(), refused_.load(),
               duplicates_.load()};
}

struct Subscriber::Connection {
  int fd = -1;
  bool proven = false;  // the peer answered the challenge: it holds the delivery key
  std::string nonce;    // hex, sent in the challenge
  std::string buf;
  std::chrono::steady_clock::time_point deadline;
};

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

void Subscriber::accept_one(std::vector<Connection>& conns) {
  int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
  if (fd < 0) return;
  ++connections_;
  if (conns.size() >= options_.max_connections) {
    // Make room by dropping the oldest connection that has not proven itself;
    // when every one has, the newcomer is the one refused.
    auto victim =
        std::find_if(conns.begin(), conns.end(), [](const Connection& c) { return !c.proven; });
    if (victim == conns.end()) {
      ++refused_;
      ::close(fd);
      return;
    }
    ++refused_;
    ::close(victim->fd);
    conns.erase(victim);
  }
  Connection c;
  c.fd = fd;
  uint8_t raw[32];
  if (::getrandom(raw, sizeof raw, 0) != ssize_t(sizeof raw)) {
    ::close(fd);
    return;
  }
  c.nonce = hex(raw, sizeof raw);
  std::string hello = std::string(kGreeting) + c.nonce + "\n";
  // A fresh socket's send buffer takes these 81 bytes at once.
  if (::send(fd, hello.data(), hello.size(), MSG_NOSIGNAL) != ssize_t(hello.size())) {
    ::close(fd);
    return;
  }
  c.deadline = Clock::now() + std::chrono::milliseconds(options_.handshake_timeout_ms);
  conns.push_back(std::move(c));
}

bool Subscriber::handle_line(Connection& c, std::string_view line) {
  if (!c.proven) {
    // The first line must be the proof; anything else (a forged value) is refused.
    if (line.substr(0, 5) != "AUTH " ||
        !equal_ct(line.substr(5), delivery_proof(options_.key, c.nonce))) {
      ++refused_;
      return false;
    }
    c.proven = true;
    return true;
  }
  if (line.empty()) return true;
  Delivered d;
  if (!parse_delivered(line, d)) {
    ++malformed_;
  } else if (!options_.keep_repeats && !seen_.first(d)) {
    ++duplicates_;  // another station's copy of a window already passed on
  } else {
    ++received_;
    callback_(d);
  }
  return true;
}

bool Subscriber::serve(Connection& c) {
  char chunk[4096];
  ssize_t n = ::recv(c.fd, chunk, sizeof chunk, 0);
  if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
  if (n == 0) return false;  // the SubBroker went away; it reconnects by itself
  c.buf.append(chunk, size_t(n));
  size_t start = 0, nl;
  while ((nl = c.buf.find('\n', start)) != std::string::npos) {
    std::string_view line(c.buf.data() + start, nl - start);
    start = nl + 1;
    if (!handle_line(c, line)) return false;
  }
  // Once proven (possibly by this very read), the idle timeout runs from the last byte.
  if (c.proven) c.deadline = Clock::now() + std::chrono::milliseconds(options_.idle_timeout_ms);
  c.buf.erase(0, start);
  if (c.buf.size() > (c.proven ? kMaxLine : 256)) {
    ++(c.proven ? malformed_ : refused_);
    return false;
  }
  return true;
}

void Subscriber::run() {
  std::vector<Connection> conns;
  std::vector<pollfd> fds;
  while (!stopping_) {
    auto now = Clock::now();
    // Drop the connections past their deadline: unproven after the handshake
    // timeout, proven after the idle timeout.
    for (auto it = conns.begin(); it != conns.end();) {
      if (it->deadline <= now) {
        ++refused_;
        ::close(it->fd);
        it = conns.erase(it);
      } else {
        ++it;
      }
    }
    int timeout = -1;
    for (const auto& c : conns) {
      auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(c.deadline - now).count() + 1;
      timeout = timeout < 0 ? int(ms) : std::min(timeout, int(ms));
    }
    fds.assign({{listen_fd_, POLLIN, 0}, {wake_[0], POLLIN, 0}});
    for (const auto& c : conns) fds.push_back({c.fd, POLLIN, 0});
    if (::poll(fds.data(), fds.size(), timeout) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    if (fds[1].revents) break;
    // Serve the connections first (indices match fds[2..]), then accept.
    std::vector<Connection> kept;
    kept.reserve(conns.size());
    for (size_t i = 0; i < conns.size(); ++i) {
      bool keep = true;
      if (fds[i + 2].revents) keep = serve(conns[i]);
      if (keep) {
        kept.push_back(std::move(conns[i]));
      } else {
        ::close(conns[i].fd);
      }
    }
    conns = std::move(kept);
    if (fds[0].revents & POLLIN) accept_one(conns);
  }
  for (auto& c : conns) ::close(c.fd);
}

}  // namespace modd
