// Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit.
// The wire constants of quantised values (modd_contracts/quantised.py,
// docs/protocol.md "Quantised values"), read by link/quantise.cpp.
#pragma once

#include <cstdint>

namespace modd::link::quantised {

// The code of a value sent exactly (f64le follows) instead of as steps.
inline constexpr uint64_t kEscape = 0;
// A step count is at most 2^this in magnitude.
inline constexpr uint64_t kMaxStepsBits = 53;
// A delta of step counts is at most 2^this in magnitude.
inline constexpr uint64_t kMaxDeltaBits = 54;

}  // namespace modd::link::quantised
