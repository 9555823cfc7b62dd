// Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit.
// Wire enumerations, counts and limits (modd_contracts/wire.json).
#pragma once

#include <cstddef>
#include <cstdint>

// The LEB128 varints of both protocols: unsigned 64-bit values.
namespace modd {

// Longest varint, in bytes (7 bits each; the tenth holds bit 63 alone).
inline constexpr int kMaxVarintBytes = 10;

}  // namespace modd
