// Declared resolution on the live link (docs/protocol.md, "Quantised values"): a
// stream's float values as integer steps, delta-coded against the same stream's
// previous value in the same unit (a DATA frame, a DATA datagram, a fragmented
// slot), as varint(zigzag(delta) + 1); code 0 escapes to the exact value (f64le)
// whenever the steps would not restore it within half a step. Mirrors
// runtime/python/src/modd/link/quantise.py.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include "modd/link/quantised.gen.hpp"
#include "modd/util/bytes.hpp"

namespace modd::link {

inline constexpr int64_t kMaxSteps = int64_t{1} << quantised::kMaxStepsBits;  // exact in a double
inline constexpr int64_t kMaxDelta = int64_t{1} << quantised::kMaxDeltaBits;

// The last step count of each stream in the unit being written or read.
class Chain {
 public:
  const int64_t* find(uint32_t stream) const;
  void set(uint32_t stream, int64_t steps);

 private:
  std::vector<std::pair<uint32_t, int64_t>> last_;  // a slot has few streams
};

// The values of one slot written against a chain (the datagram's): how the
// executor hands a slot with quantised streams to the datagram packer.
using SlotEncoder = std::function<std::vector<uint8_t>(Chain&)>;

// round(x / r) (to nearest, ties to even) when q * r restores x within r / 2.
std::optional<int64_t> quantise_steps(double x, double resolution);
void put_number(ByteWriter& w, Chain& chain, uint32_t stream, double x, double resolution);
double get_number(ByteReader& r, Chain& chain, uint32_t stream, double resolution);

}  // namespace modd::link
