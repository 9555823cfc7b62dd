// Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit.
// Wire enumerations, counts and limits (modd_contracts/wire.json).
#pragma once

#include <cstddef>
#include <cstdint>

// The PubBroker's ingress protocol (docs/ingress.md).
namespace modd::ingress {

// Protocol version; 2 adds the broker's answers (CATALOGUE, ACK, REJECT).
inline constexpr uint8_t kVersion = 2;
// Oldest version a broker accepts (a version-1 publisher gets no answers).
inline constexpr uint8_t kMinVersion = 1;
// Largest frame, in bytes after the length prefix.
inline constexpr size_t kMaxFrame = 1048576;
// Largest local topic id of a publisher.
inline constexpr uint64_t kMaxLocalId = 65535;
// Longest topic, publisher or drone name and REJECT detail, in bytes.
inline constexpr size_t kMaxName = 255;

// The type byte of a frame: publisher -> broker below 0x80, broker -> publisher (version 2)
// above.
enum class MsgType : uint8_t {
  Hello = 0x01,
  Register = 0x02,
  Samples = 0x03,
  Health = 0x04,
  Catalogue = 0x81,
  Ack = 0x82,
  Reject = 0x83,
};
// The number of MsgType values.
inline constexpr size_t kMsgTypeCount = 7;

}  // namespace modd::ingress
