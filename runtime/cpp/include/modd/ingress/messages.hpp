// Messages of the local ingress protocol (docs/ingress.md): a publisher says
// hello, registers topic names once with a local id and a type, then sends
// batches of (local id, publisher timestamp, value) records.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "modd/link/messages.hpp"

namespace modd::ingress {

using link::ValueType;
inline constexpr uint8_t kVersion = 1;
inline constexpr size_t kMaxFrame = 1 << 20;

enum class MsgType : uint8_t { Hello = 0x01, Register = 0x02, Samples = 0x03 };

struct Hello { uint8_t version = kVersion; std::string publisher; };
struct Register { uint32_t local_id = 0; ValueType type = ValueType::Float32; std::string topic; };

// One record of a SAMPLES batch. Ints and bools travel in `integer`.
struct Record {
  uint32_t local_id = 0;
  int64_t timestamp_ns = 0;
  double number = 0;
  int64_t integer = 0;
};

inline size_t value_width(ValueType t) {
  switch (t) {
    case ValueType::Float32: return 4;
    case ValueType::Float64: return 8;
    case ValueType::Int: return 8;
    case ValueType::Bool: return 1;
  }
  return 0;
}

}  // namespace modd::ingress
