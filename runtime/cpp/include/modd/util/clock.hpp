// Clocks behind an interface so that the schedule executor and the broker can
// be driven by a fake clock in tests.
#pragma once
#include <cstdint>

namespace modd {

class Clock {
 public:
  virtual ~Clock() = default;
  // Wall-clock time (CLOCK_REALTIME) in ns: the broker's sample stamps and slot dates.
  virtual int64_t now_ns() = 0;
};

class SystemClock final : public Clock {
 public:
  int64_t now_ns() override;
};

class FakeClock final : public Clock {
 public:
  explicit FakeClock(int64_t t = 1'000'000'000'000'000'000) : t_(t) {}
  int64_t now_ns() override { return t_; }
  void set(int64_t t) { t_ = t; }
  void advance(int64_t dt) { t_ += dt; }

 private:
  int64_t t_;
};

}  // namespace modd
