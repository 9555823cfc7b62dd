#include "modd/link/quantise.hpp"

#include <cmath>
#include <string>

namespace modd::link {

namespace {
constexpr uint64_t kEscape = quantised::kEscape;
}

const int64_t* Chain::find(uint32_t stream) const {
  for (const auto& [s, q] : last_)
    if (s == stream) return &q;
  return nullptr;
}

void Chain::set(uint32_t stream, int64_t steps) {
  for (auto& [s, q] : last_)
    if (s == stream) {
      q = steps;
      return;
    }
  last_.emplace_back(stream, steps);
}

std::optional<int64_t> quantise_steps(double x, double resolution) {
  if (!std::isfinite(x)) return std::nullopt;
  double ratio = x / resolution;
  if (!std::isfinite(ratio) || std::fabs(ratio) > static_cast<double>(kMaxSteps))
    return std::nullopt;
  double q = std::nearbyint(ratio);  // the default rounding mode: to nearest, ties to even
  if (std::fabs(q * resolution - x) > resolution / 2) return std::nullopt;
  return static_cast<int64_t>(q);
}

void put_number(ByteWriter& w, Chain& chain, uint32_t stream, double x, double resolution) {
  auto q = quantise_steps(x, resolution);
  if (!q) {
    w.varint(kEscape);
    w.fixed<double>(x);
    return;
  }
  const int64_t* prev = chain.find(stream);
  w.varint(zigzag_encode(prev ? *q - *prev : *q) + 1);
  chain.set(stream, *q);
}

double get_number(ByteReader& r, Chain& chain, uint32_t stream, double resolution) {
  uint64_t code = r.varint();
  if (code == kEscape) return r.fixed<double>();
  int64_t delta = zigzag_decode(code - 1);
  if (delta > kMaxDelta || delta < -kMaxDelta)
    r.fail("quantised delta " + std::to_string(delta) + " beyond 2^54 steps");
  const int64_t* prev = chain.find(stream);
  int64_t q = prev ? *prev + delta : delta;
  if (q > kMaxSteps || q < -kMaxSteps)
    r.fail("quantised value of " + std::to_string(q) + " steps beyond 2^53");
  chain.set(stream, q);
  return static_cast<double>(q) * resolution;
}

}  // namespace modd::link
