// A token bucket on the broker's timeline (ns): `rate` tokens a second, at most `burst`
// held. Used to bound what a peer can make the drone send (CHALLENGEs, NACK resends).
#pragma once
#include <algorithm>
#include <cstdint>

namespace modd {

class TokenBucket {
 public:
  // Starts full, or with `initial` tokens.
  TokenBucket(double rate_per_s, double burst, double initial = -1)
      : rate_(rate_per_s), burst_(burst), tokens_(initial < 0 ? burst : initial) {}
  // Takes `n` tokens if there are that many now; false (nothing taken) otherwise.
  bool take(int64_t now, double n = 1) {
    refill(now);
    if (tokens_ < n) return false;
    tokens_ -= n;
    return true;
  }
  // Adds tokens earned otherwise than by time (resends: live bytes sent), up to the burst.
  void earn(double n) { tokens_ = std::min(burst_, tokens_ + n); }
  double tokens(int64_t now) {
    refill(now);
    return tokens_;
  }

 private:
  void refill(int64_t now) {
    if (started_ && now > last_)
      tokens_ = std::min(burst_, tokens_ + rate_ * static_cast<double>(now - last_) / 1e9);
    if (!started_ || now > last_) last_ = now;
    started_ = true;
  }
  double rate_, burst_, tokens_;
  int64_t last_ = 0;
  bool started_ = false;
};

}  // namespace modd
