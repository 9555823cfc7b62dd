#include "modd/util/log.hpp"

#include <cstdarg>
#include <cstdio>
#include <ctime>

namespace modd {

void log_line(const char* fmt, ...) {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  std::tm tm{};
  gmtime_r(&ts.tv_sec, &tm);
  char head[48];
  std::strftime(head, sizeof head, "%Y-%m-%dT%H:%M:%S", &tm);
  char msg[1024];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  std::fprintf(stderr, "%s.%03ldZ modd-pubbroker: %s\n", head, ts.tv_nsec / 1000000, msg);
}

}  // namespace modd
