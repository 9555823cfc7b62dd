#include "modd/broker/dgram_port.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "modd/link/datagram.hpp"
#include "modd/util/error.hpp"

namespace modd::broker {

namespace {

constexpr size_t kMaxUdp = 65535;
constexpr size_t kSerialBacklog =
    16 * 1024;  // unsent serial bytes above which a datagram is dropped

[[noreturn]] void sys_fail(const std::string& what) {
  throw Error(ErrorCode::Io, what + ": " + std::strerror(errno));
}

class UdpPort final : public DgramPort {
 public:
  UdpPort(const std::string& host, uint16_t port, uint16_t& bound) {
    fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd_ < 0) sys_fail("socket");
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    if (inet_pton(AF_INET, host.c_str(), &a.sin_addr) != 1)
      throw Error(ErrorCode::BadConfig, "bad IPv4 address " + host);
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) < 0)
      sys_fail("bind udp " + host + ":" + std::to_string(port));
    socklen_t len = sizeof a;
    getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    bound = ntohs(a.sin_port);
    where_ = "udp " + host + ":" + std::to_string(bound);
  }
  ~UdpPort() override { ::close(fd_); }
  int fd() const override { return fd_; }
  std::string describe() const override { return where_; }

  void read(const std::function<void(std::span<const uint8_t>)>& fn) override {
    std::vector<uint8_t> buf(kMaxUdp);
    for (int i = 0; i < 64; ++i) {  // bounded per wake-up
      source_len_ = sizeof source_;
      ssize_t n = ::recvfrom(fd_, buf.data(), buf.size(), 0, reinterpret_cast<sockaddr*>(&source_),
                             &source_len_);
      if (n < 0) return;  // EAGAIN, or an ICMP error of an earlier send: nothing to read
      bytes_in += static_cast<uint64_t>(n);
      fn(std::span<const uint8_t>(buf.data(), static_cast<size_t>(n)));
    }
  }

  void send(std::vector<uint8_t>&& d, bool reply) override {
    const sockaddr_storage& to = reply ? source_ : peer_;
    socklen_t len = reply ? source_len_ : peer_len_;
    if (len == 0) return;
    if (::sendto(fd_, d.data(), d.size(), MSG_NOSIGNAL, reinterpret_cast<const sockaddr*>(&to),
                 len) < 0)
      ++dropped_out;
    else
      bytes_out += d.size();
  }

  void adopt_source() override {
    peer_ = source_;
    peer_len_ = source_len_;
  }
  std::vector<uint8_t> source() const override {
    const auto* p = reinterpret_cast<const uint8_t*>(&source_);
    return {p, p + source_len_};
  }
  bool from_peer() const override {
    return peer_len_ == source_len_ && std::memcmp(&peer_, &source_, source_len_) == 0;
  }

 private:
  int fd_ = -1;
  std::string where_;
  sockaddr_storage source_{}, peer_{};
  socklen_t source_len_ = 0, peer_len_ = 0;
};

speed_t speed_of(uint32_t baud) {
  switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 921600: return B921600;
    default: return 0;
  }
}

class SerialPort final : public DgramPort {
 public:
  SerialPort(const std::string& device, uint32_t baud, size_t max_frame)
      : deframer_(max_frame), where_("serial " + device) {
    fd_ = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) sys_fail("open " + device);
    termios t{};
    if (tcgetattr(fd_, &t) == 0) {
      cfmakeraw(&t);
      t.c_cflag |= CLOCAL | CREAD;
      t.c_cflag &= ~CRTSCTS;
      if (speed_t s = speed_of(baud)) {
        cfsetispeed(&t, s);
        cfsetospeed(&t, s);
      }
      t.c_cc[VMIN] = 0;
      t.c_cc[VTIME] = 0;
      tcsetattr(fd_, TCSANOW, &t);
    }
    if (speed_of(baud) == 0 && baud != 0)
      throw Error(ErrorCode::BadConfig, device + ": unsupported baud rate " + std::to_string(baud));
  }
  ~SerialPort() override { ::close(fd_); }
  int fd() const override { return fd_; }
  std::string describe() const override { return where_; }

  void read(const std::function<void(std::span<const uint8_t>)>& fn) override {
    uint8_t buf[4096];
    for (int i = 0; i < 16; ++i) {
      ssize_t n = ::read(fd_, buf, sizeof buf);
      if (n < 0 && errno == EIO) broken_ = true;  // a pseudo-terminal whose other end closed
      if (n <= 0) break;
      bytes_in += static_cast<uint64_t>(n);
      for (auto& d : deframer_.feed(std::span<const uint8_t>(buf, static_cast<size_t>(n)))) fn(d);
    }
    corrupt = deframer_.corrupt() + deframer_.oversized();
  }

  void send(std::vector<uint8_t>&& d, bool) override {
    if (out_.size() > kSerialBacklog) {
      ++dropped_out;
      return;
    }
    auto frame = link::dgram::encode_frame(d);
    out_.insert(out_.end(), frame.begin(), frame.end());
    flush_pending();
  }

  bool flush_pending() override {
    while (!out_.empty()) {
      ssize_t n = ::write(fd_, out_.data(), out_.size());
      if (n <= 0) break;
      bytes_out += static_cast<uint64_t>(n);
      out_.erase(out_.begin(), out_.begin() + n);
    }
    return out_.empty();
  }

  void adopt_source() override {}
  bool broken() const override { return broken_; }

 private:
  int fd_ = -1;
  bool broken_ = false;
  link::dgram::Deframer deframer_;
  std::vector<uint8_t> out_;
  std::string where_;
};

}  // namespace

std::unique_ptr<DgramPort> open_udp(const std::string& host, uint16_t port, uint16_t& bound) {
  return std::make_unique<UdpPort>(host, port, bound);
}

std::unique_ptr<DgramPort> open_serial(const std::string& device, uint32_t baud, size_t max_frame) {
  return std::make_unique<SerialPort>(device, baud, max_frame);
}

}  // namespace modd::broker
