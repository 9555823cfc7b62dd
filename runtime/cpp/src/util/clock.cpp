#include "modd/util/clock.hpp"

#include <ctime>

namespace modd {

namespace {
int64_t read(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}
}  // namespace

int64_t SystemClock::now_ns() { return read(CLOCK_REALTIME); }
int64_t SystemClock::mono_ns() { return read(CLOCK_MONOTONIC); }

Timeline::Timeline(Clock& c) : clock_(c) {
  wall_ = clock_.now_ns();
  anchor_ = wall_ - clock_.mono_ns();
}

int64_t Timeline::now() {
  wall_ = clock_.now_ns();
  int64_t t = anchor_ + clock_.mono_ns();
  int64_t offset = wall_ - t, delta = offset - offset_;
  last_ = {t, 0};
  if (delta > kStepNs || delta < -kStepNs) {
    ++steps_;
    last_ = {t, delta};
  }
  offset_ = offset;
  return t;
}

}  // namespace modd
