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

// Why the broker refused a record: the reason code of REJECT, and the index of the PubBroker's
// rejected_* counters (labels: their log names).
enum class Reject : uint8_t {
  UnknownTopic = 0,  // unknown topic
  WrongType = 1,  // wrong type
  NotFinite = 2,  // value not finite
  Timestamp = 3,  // timestamp out of bounds
  Overflow = 4,  // archive queue full
  Malformed = 5,  // malformed
  Quota = 6,  // over its fair share of the archive queue
};
// The number of Reject values.
inline constexpr size_t kRejectCount = 7;
// Each Reject's name in logs and status documents, by code.
inline constexpr const char* kRejectLabels[] = {"unknown_topic", "wrong_type", "not_finite", "timestamp", "overflow", "malformed", "quota"};

}  // namespace modd::ingress
