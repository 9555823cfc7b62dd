// The ingress wire (docs/ingress.md), written once for both ends: the
// PubBroker's codec (src/ingress/codec.cpp) and the publisher client
// (src/client/publisher.cpp). Versions, message types, the frame limit and
// the writer of a frame and its fields. Standard library only: it travels
// with the client into generated driver projects (modd/include/modd/ingress).
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

namespace modd::ingress {

// Version 2 adds the broker's answers (CATALOGUE, ACK, REJECT); a version-1 publisher
// gets none of them (the broker never writes to it).
inline constexpr uint8_t kVersion = 2;
inline constexpr uint8_t kMinVersion = 1;
inline constexpr size_t kMaxFrame = 1 << 20;  // bytes after the length prefix

// One line a direction.
// clang-format off
enum class MsgType : uint8_t {
  Hello = 0x01, Register = 0x02, Samples = 0x03, Health = 0x04,  // publisher -> broker
  Catalogue = 0x81, Ack = 0x82, Reject = 0x83,    // broker -> publisher (version 2)
};
// clang-format on

namespace wire {

// LEB128 varint.
inline void put_varint(std::vector<uint8_t>& b, uint64_t v) {
  while (v >= 0x80) {
    b.push_back(static_cast<uint8_t>(v | 0x80));
    v >>= 7;
  }
  b.push_back(static_cast<uint8_t>(v));
}
// Little-endian fixed-width value (the project targets little-endian hosts).
template <typename T>
void put_fixed(std::vector<uint8_t>& b, T v) {
  uint8_t x[sizeof(T)];
  std::memcpy(x, &v, sizeof(T));
  b.insert(b.end(), x, x + sizeof(T));
}
// Varint length, then the bytes.
inline void put_string(std::vector<uint8_t>& b, std::string_view s) {
  put_varint(b, s.size());
  b.insert(b.end(), s.begin(), s.end());
}
// One frame: varint length (type byte and body), type byte, body.
inline void put_frame(std::vector<uint8_t>& out, MsgType type, const std::vector<uint8_t>& body) {
  put_varint(out, body.size() + 1);
  out.push_back(static_cast<uint8_t>(type));
  out.insert(out.end(), body.begin(), body.end());
}

}  // namespace wire
}  // namespace modd::ingress
