// Clocks behind an interface so that the schedule executor and the broker can
// be driven by a fake clock in tests, and the broker's timeline that a wall-clock
// step cannot move (docs/pubbroker.md, "Clock steps").
#pragma once
#include <cstdint>

namespace modd {

class Clock {
 public:
  virtual ~Clock() = default;
  // Wall-clock time (CLOCK_REALTIME) in ns: what publishers' timestamps are judged against.
  virtual int64_t now_ns() = 0;
  // Monotonic time (CLOCK_MONOTONIC) in ns: never steps, only elapses.
  virtual int64_t mono_ns() = 0;
};

class SystemClock final : public Clock {
 public:
  int64_t now_ns() override;
  int64_t mono_ns() override;
};

// Wall time and elapsed time apart: advance() lets time pass, step() sets the wall clock
// (a GPS or NTP correction) without any time passing.
class FakeClock final : public Clock {
 public:
  explicit FakeClock(int64_t t = 1'000'000'000'000'000'000) : t_(t) {}
  int64_t now_ns() override { return t_; }
  int64_t mono_ns() override { return mono_; }
  // Time passes up to wall time t (a t in the past is a step back: no time passes).
  void set(int64_t t) {
    if (t > t_) mono_ += t - t_;
    t_ = t;
  }
  void advance(int64_t dt) {
    t_ += dt;
    mono_ += dt;
  }
  void step(int64_t dt) { t_ += dt; }

 private:
  int64_t t_;
  int64_t mono_ = 5'000'000'000;
};

// The broker's time: the wall clock read at start plus the monotonic time elapsed since.
// Stamps, slot dates and timers use it, so a wall-clock step is neither elapsed time (no
// slot walked) nor a pause (no slot held); each step is counted and the offset kept.
class Timeline {
 public:
  // A change of (wall - timeline) larger than this between two readings is a step; slower
  // drifts (NTP slewing, at most 0.5 ms/s) only move the offset.
  static constexpr int64_t kStepNs = 100'000'000;
  struct Step {
    int64_t at_ns;     // timeline time of the reading that saw it
    int64_t delta_ns;  // how far the wall clock moved against the timeline (+ forward)
  };

  explicit Timeline(Clock& c);
  // Reads both clocks: the timeline time; wall() is the wall time of the same reading.
  int64_t now();
  int64_t wall() const { return wall_; }
  int64_t offset_ns() const { return offset_; }  // wall - timeline, as last read
  uint64_t steps() const { return steps_; }
  // The step the last now() saw, if it saw one (for a log line), else delta 0.
  Step last_step() const { return last_; }

 private:
  Clock& clock_;
  int64_t anchor_ = 0, wall_ = 0, offset_ = 0;
  uint64_t steps_ = 0;
  Step last_{0, 0};
};

}  // namespace modd
