// systemd's service notification protocol (sd_notify(3)) without libsystemd: each
// state is one datagram ("READY=1", "WATCHDOG=1", ...) sent to the AF_UNIX socket
// named by $NOTIFY_SOCKET (a leading '@' names an abstract socket). A unit with
// Type=notify waits for READY=1; with WatchdogSec= it kills and restarts the service
// when no WATCHDOG=1 arrives within $WATCHDOG_USEC, so a hung main loop is restarted.
// Not started by systemd (no $NOTIFY_SOCKET): every call does nothing.
//
//   SdNotifier n = SdNotifier::from_env(clock);
//   n.ready("listening");             // once the archive and listeners are up
//   loop { ...; n.tick(); }           // feeds the watchdog at half its period
#pragma once
#include <cstdint>
#include <string>
#include <string_view>

#include "modd/util/clock.hpp"

namespace modd {

class SdNotifier {
 public:
  // socket_path: $NOTIFY_SOCKET ("" = off); watchdog_usec: $WATCHDOG_USEC (0 = no watchdog).
  SdNotifier(Clock& clock, std::string socket_path, uint64_t watchdog_usec);
  // From the environment; the watchdog only if $WATCHDOG_PID is unset or this process.
  static SdNotifier from_env(Clock& clock);
  ~SdNotifier();
  SdNotifier(SdNotifier&& o) noexcept;
  SdNotifier(const SdNotifier&) = delete;
  SdNotifier& operator=(const SdNotifier&) = delete;
  SdNotifier& operator=(SdNotifier&&) = delete;

  bool active() const { return fd_ >= 0; }
  // One datagram with these newline-separated assignments; false if it could not be sent.
  bool notify(std::string_view state);
  // READY=1 with a STATUS= line.
  bool ready(std::string_view status);
  bool stopping() { return notify("STOPPING=1"); }
  // WATCHDOG=1 when half the watchdog period has passed since the last one (monotonic).
  void tick();
  // Milliseconds until tick() must run again (a bound for the loop's wait); -1: never.
  int ms_until_due();
  uint64_t interval_ns() const { return interval_ns_; }

 private:
  Clock& clock_;
  std::string path_;
  int fd_ = -1;
  uint64_t interval_ns_ = 0;  // half of WATCHDOG_USEC, in ns; 0: no watchdog
  int64_t next_ns_ = 0;
};

}  // namespace modd
