// systemd's notify protocol, read back from a real AF_UNIX datagram socket standing in
// for systemd's (path and abstract), with a fake clock driving the watchdog period.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <string>

#include "modd/util/clock.hpp"
#include "modd/util/sd_notify.hpp"

namespace {

// A bound datagram socket: what systemd listens on. abstract: '@name' instead of a path.
class FakeSystemd {
 public:
  explicit FakeSystemd(bool abstract) {
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    std::string name = "modd-sd-test-" + std::to_string(::getpid()) + (abstract ? "-a" : "-p");
    sockaddr_un sa{};
    sa.sun_family = AF_UNIX;
    if (abstract) {
      path_ = "@" + name;
      std::memcpy(sa.sun_path + 1, name.data(), name.size());
    } else {
      path_ = "/tmp/" + name;
      ::unlink(path_.c_str());
      std::memcpy(sa.sun_path, path_.data(), path_.size());
    }
    socklen_t len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path_.size());
    EXPECT_EQ(::bind(fd_, reinterpret_cast<sockaddr*>(&sa), len), 0) << std::strerror(errno);
    timeval tv{0, 200'000};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  }
  ~FakeSystemd() {
    ::close(fd_);
    if (path_[0] == '/') ::unlink(path_.c_str());
  }
  const std::string& path() const { return path_; }
  // The next datagram, or "" if none came within 200 ms.
  std::string next() {
    char buf[512];
    ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    return n > 0 ? std::string(buf, static_cast<size_t>(n)) : std::string();
  }

 private:
  int fd_ = -1;
  std::string path_;
};

}  // namespace

TEST(SdNotify, ReadyAndStoppingReachThePathSocket) {
  FakeSystemd sd(false);
  modd::FakeClock clock;
  modd::SdNotifier n(clock, sd.path(), 0);
  ASSERT_TRUE(n.active());
  EXPECT_TRUE(n.ready("archiving to /var/lib/modd"));
  EXPECT_EQ(sd.next(), "READY=1\nSTATUS=archiving to /var/lib/modd");
  EXPECT_TRUE(n.stopping());
  EXPECT_EQ(sd.next(), "STOPPING=1");
  n.tick();  // no watchdog asked: nothing sent, and no bound on the loop's wait
  EXPECT_EQ(sd.next(), "");
  EXPECT_EQ(n.ms_until_due(), -1);
}

TEST(SdNotify, AbstractSocketAddress) {
  FakeSystemd sd(true);
  modd::FakeClock clock;
  modd::SdNotifier n(clock, sd.path(), 0);
  EXPECT_TRUE(n.notify("READY=1"));
  EXPECT_EQ(sd.next(), "READY=1");
}

TEST(SdNotify, WatchdogFedAtHalfItsPeriod) {
  FakeSystemd sd(false);
  modd::FakeClock clock;
  modd::SdNotifier n(clock, sd.path(), 10'000'000);  // WATCHDOG_USEC=10 s
  EXPECT_EQ(n.interval_ns(), 5'000'000'000u);
  n.tick();  // the first at once
  EXPECT_EQ(sd.next(), "WATCHDOG=1");
  EXPECT_EQ(n.ms_until_due(), 5000);
  clock.advance(4'999'000'000);
  n.tick();
  EXPECT_EQ(sd.next(), "");  // not yet due
  EXPECT_EQ(n.ms_until_due(), 1);
  clock.advance(1'000'000);
  n.tick();
  EXPECT_EQ(sd.next(), "WATCHDOG=1");
  clock.step(-3'600'000'000'000);  // a wall-clock step back changes nothing: monotonic time
  clock.advance(5'000'000'000);
  n.tick();
  EXPECT_EQ(sd.next(), "WATCHDOG=1");
}

TEST(SdNotify, FromEnvironment) {
  FakeSystemd sd(false);
  modd::FakeClock clock;
  ::setenv("NOTIFY_SOCKET", sd.path().c_str(), 1);
  ::setenv("WATCHDOG_USEC", "2000000", 1);
  ::setenv("WATCHDOG_PID", std::to_string(::getpid()).c_str(), 1);
  {
    auto n = modd::SdNotifier::from_env(clock);
    EXPECT_EQ(n.interval_ns(), 1'000'000'000u);
  }
  ::setenv("WATCHDOG_PID", "1", 1);  // the watchdog is another process's
  EXPECT_EQ(modd::SdNotifier::from_env(clock).interval_ns(), 0u);
  ::unsetenv("WATCHDOG_PID");
  ::unsetenv("WATCHDOG_USEC");
  ::unsetenv("NOTIFY_SOCKET");
  auto off = modd::SdNotifier::from_env(clock);  // not under systemd: a no-op
  EXPECT_FALSE(off.active());
  EXPECT_FALSE(off.notify("READY=1"));
  ::setenv("NOTIFY_SOCKET", "relative/path", 1);  // not an address: refused, no crash
  EXPECT_FALSE(modd::SdNotifier::from_env(clock).active());
  ::unsetenv("NOTIFY_SOCKET");
}
