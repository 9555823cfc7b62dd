// sd_notify(3)'s wire protocol: an unconnected AF_UNIX datagram per notification.
#include "modd/util/sd_notify.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <utility>

#include "modd/util/log.hpp"

namespace modd {

namespace {

// The address of $NOTIFY_SOCKET: a path, or '@name' for an abstract socket.
bool notify_address(const std::string& path, sockaddr_un& sa, socklen_t& len) {
  std::memset(&sa, 0, sizeof sa);
  sa.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof sa.sun_path) return false;
  if (path[0] != '/' && path[0] != '@') return false;
  std::memcpy(sa.sun_path, path.data(), path.size());
  if (path[0] == '@') sa.sun_path[0] = '\0';
  len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path.size());
  return true;
}

uint64_t env_u64(const char* name) {
  const char* v = std::getenv(name);
  if (!v || !*v) return 0;
  char* end = nullptr;
  unsigned long long n = std::strtoull(v, &end, 10);
  return (end && *end == '\0') ? n : 0;
}

}  // namespace

SdNotifier::SdNotifier(Clock& clock, std::string socket_path, uint64_t watchdog_usec)
    : clock_(clock), path_(std::move(socket_path)) {
  if (path_.empty()) return;
  sockaddr_un sa;
  socklen_t len = 0;
  if (!notify_address(path_, sa, len)) {
    log_line("systemd: NOTIFY_SOCKET '%s' is not a socket address; not notifying", path_.c_str());
    return;
  }
  fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  interval_ns_ = watchdog_usec * 1000 / 2;
  next_ns_ = clock_.mono_ns();  // the first tick feeds at once
}

SdNotifier SdNotifier::from_env(Clock& clock) {
  const char* sock = std::getenv("NOTIFY_SOCKET");
  uint64_t usec = env_u64("WATCHDOG_USEC");
  uint64_t pid = env_u64("WATCHDOG_PID");
  if (pid && pid != static_cast<uint64_t>(::getpid())) usec = 0;  // meant for another process
  return SdNotifier(clock, sock ? sock : "", usec);
}

SdNotifier::SdNotifier(SdNotifier&& o) noexcept
    : clock_(o.clock_),
      path_(std::move(o.path_)),
      fd_(std::exchange(o.fd_, -1)),
      interval_ns_(o.interval_ns_),
      next_ns_(o.next_ns_) {}

SdNotifier::~SdNotifier() {
  if (fd_ >= 0) ::close(fd_);
}

bool SdNotifier::notify(std::string_view state) {
  if (fd_ < 0) return false;
  sockaddr_un sa;
  socklen_t len = 0;
  notify_address(path_, sa, len);
  ssize_t n = ::sendto(fd_, state.data(), state.size(), MSG_NOSIGNAL,
                       reinterpret_cast<const sockaddr*>(&sa), len);
  return n == static_cast<ssize_t>(state.size());
}

bool SdNotifier::ready(std::string_view status) {
  std::string msg = "READY=1\nSTATUS=";
  msg.append(status);
  return notify(msg);
}

void SdNotifier::tick() {
  if (fd_ < 0 || interval_ns_ == 0) return;
  int64_t now = clock_.mono_ns();
  if (now < next_ns_) return;
  notify("WATCHDOG=1");
  next_ns_ = now + static_cast<int64_t>(interval_ns_);
}

int SdNotifier::ms_until_due() {
  if (fd_ < 0 || interval_ns_ == 0) return -1;
  int64_t left = next_ns_ - clock_.mono_ns();
  return left <= 0 ? 0 : static_cast<int>((left + 999'999) / 1'000'000);
}

}  // namespace modd
