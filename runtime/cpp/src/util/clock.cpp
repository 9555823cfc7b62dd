#include "modd/util/clock.hpp"

#include <ctime>

namespace modd {

int64_t SystemClock::now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace modd
