// Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit.
// Wire enumerations, counts and limits (modd_contracts/wire.json).
#pragma once

#include <cstddef>
#include <cstdint>

// The link protocol's frames (docs/protocol.md).
namespace modd::link {

// Protocol version of HELLO and CHALLENGE.
inline constexpr uint8_t kVersion = 1;
// Largest frame, in bytes after the length prefix.
inline constexpr size_t kMaxFrame = 1048576;
// Largest accepted delay a CONFIG may carry (one hour, as the PubBroker's link.delay_ms).
inline constexpr uint32_t kMaxAcceptedDelayMs = 3600000;
// Largest PING or PONG payload, in bytes.
inline constexpr size_t kMaxPing = 64;
// Most instruments in one STATUS or HEALTH (docs/protocol.md, STATUS).
inline constexpr size_t kMaxHealthSensors = 64;
// Most counters of one instrument's health.
inline constexpr size_t kMaxHealthFields = 32;
// Longest instrument name in a health report, in bytes.
inline constexpr size_t kMaxHealthName = 64;
// Largest health field or STATUS counter forwarded: 2^53 - 1, exact in a double (a larger one
// is clamped by the PubBroker, left out by the SubBroker).
inline constexpr uint64_t kMaxHealthCount = 9007199254740991;
// Latest last_value_ms of an instrument's health: 2100-01-01T00:00Z in Unix ms (a later one
// reads as 0, none).
inline constexpr uint64_t kMaxLastValueMs = 4102444800000;
// Longest STATUS period a CONFIG may ask for, in seconds: one day (0: no STATUS).
inline constexpr uint64_t kMaxStatusPeriodS = 86400;
// The STATUS period the SubBroker asks for in CONFIG unless configured
// (link.pubbroker_status_period_s), and the planner counts.
inline constexpr uint64_t kDefaultStatusPeriodS = 60;
// Most topics, or streams, of one CONFIG.
inline constexpr size_t kMaxList = 65535;
// Longest topic name, in bytes.
inline constexpr size_t kMaxName = 255;
// Largest buffer size of a CONFIG topic (the smallest is 1).
inline constexpr uint64_t kMaxBufferSize = 1000000;
// Longest stream period of a CONFIG or a backfill request, in microseconds: 366 days (the
// smallest is 1).
inline constexpr uint64_t kMaxPeriodUs = 31622400000000;
// Largest on-board model (ONBOARD) or answer (ONBOARD_ACK), in bytes once decompressed.
inline constexpr size_t kMaxOnboardBytes = 262144;
// Largest compressed on-board model an ONBOARD frame carries: 16 control fragments of a 240-B
// packet.
inline constexpr size_t kMaxOnboardWire = 3584;
// How long the PubBroker waits for the on-board processes' answers before ONBOARD_ACK.
inline constexpr uint32_t kOnboardWaitMs = 2000;
// Shortest pre-shared key, in bytes: shorter keys are refused.
inline constexpr size_t kMinKeyBytes = 16;

// The PubBroker's counters in the order STATUS carries them (docs/protocol.md, STATUS); fields
// are only ever appended. The labels (lower case) name them in logs, the run record and the
// SubBroker's status.
enum class StatusField : uint8_t {
  UptimeS = 0,
  SamplesIn = 1,
  SamplesArchived = 2,
  RejectedUnknownTopic = 3,
  RejectedWrongType = 4,
  RejectedNotFinite = 5,
  RejectedTimestamp = 6,
  RejectedOverflow = 7,
  RejectedMalformed = 8,
  ArchiveFailed = 9,
  IngressMalformedFrames = 10,
  PublishersConnected = 11,
  FramesSent = 12,
  FramesDropped = 13,
  LinkBytesSent = 14,
  DiskFreeMb = 15,
  BufferFillPct = 16,
  ArchiveFiles = 17,
  AuthFailures = 18,
  ConfigId = 19,
  RejectedQuota = 20,
  ArchiveState = 21,
  ArchiveRateBps = 22,
  SamplesPending = 23,
  LinkDatagramsSent = 24,
  LinkDatagramsResent = 25,
  LinkNacks = 26,
  LinkSlotsDropped = 27,
  LinkForged = 28,
  LinkReplayed = 29,
  Instruments = 30,
  InstrumentsOpen = 31,
  InstrumentsSilent = 32,
  InstrumentsClosed = 33,
  InstrumentsUnlisted = 34,
  HealthCorrected = 35,
  StatusCoalesced = 36,
};
// The number of StatusField values.
inline constexpr size_t kStatusFieldCount = 37;
// Each StatusField's name in logs and status documents, by code.
inline constexpr const char* kStatusFieldLabels[] = {"uptime_s", "samples_in", "samples_archived", "rejected_unknown_topic", "rejected_wrong_type", "rejected_not_finite", "rejected_timestamp", "rejected_overflow", "rejected_malformed", "archive_failed", "ingress_malformed_frames", "publishers_connected", "frames_sent", "frames_dropped", "link_bytes_sent", "disk_free_mb", "buffer_fill_pct", "archive_files", "auth_failures", "config_id", "rejected_quota", "archive_state", "archive_rate_bps", "samples_pending", "link_datagrams_sent", "link_datagrams_resent", "link_nacks", "link_slots_dropped", "link_forged", "link_replayed", "instruments", "instruments_open", "instruments_silent", "instruments_closed", "instruments_unlisted", "health_corrected", "status_coalesced"};

// The type byte of a frame.
enum class MsgType : uint8_t {
  Hello = 0x01,
  Challenge = 0x02,
  Auth = 0x03,
  AuthOk = 0x04,
  Ping = 0x05,
  Pong = 0x06,
  Config = 0x07,
  ConfigAck = 0x08,
  Onboard = 0x0B,  // config id, the on-board model (zstd): for modd-sensors and modd-mavlink
  OnboardAck = 0x0C,  // config id, status, what each on-board process did (zstd JSON)
  Data = 0x10,  // seq8, values (all streams present)
  DataBitmap = 0x11,  // seq8, presence bitmap, values
  DataSync = 0x12,  // config id, full slot number, values
  DataSyncBitmap = 0x13,  // config id, full slot number, presence bitmap, values
  Status = 0x20,
  Error = 0x7F,
};
// The number of MsgType values.
inline constexpr size_t kMsgTypeCount = 16;

// A topic's value type: the metamodel's ValueType enum, coded in its order.
enum class ValueType : uint8_t {
  Float32 = 0,
  Float64 = 1,
  Int = 2,
  Bool = 3,
};
// The number of ValueType values.
inline constexpr size_t kValueTypeCount = 4;
// The metamodel's label of each ValueType, by code.
inline constexpr const char* kValueTypeLabels[] = {"float32", "float64", "int", "bool"};

}  // namespace modd::link

// Backfill frames of the link (docs/protocol.md, "Backfill").
namespace modd::link::backfill {

// Most windows of one request.
inline constexpr uint64_t kMaxWindows = 4294967295;
// Most windows of one BACKFILL_DATA frame.
inline constexpr size_t kMaxBatch = 65535;

// The type byte of a backfill frame.
enum class Type : uint8_t {
  Request = 0x50,
  Data = 0x51,
  Progress = 0x52,
  End = 0x53,
  Cancel = 0x54,
};
// The number of Type values.
inline constexpr size_t kTypeCount = 5;

// How a backfill ended (BACKFILL_END).
enum class EndStatus : uint8_t {
  Done = 0,  // every window from the resume point to the end was sent
  Cancelled = 1,  // a BACKFILL_CANCEL (or a newer request with the same id) stopped it
  UnknownTopic = 2,  // the broker has no such topic in its archive
  BadRequest = 3,  // type differs from the archive's, or the range is out of bounds
  Busy = 4,  // too many backfills at once: ask again later
  Io = 5,  // the archive could not be read
};
// The number of EndStatus values.
inline constexpr size_t kEndStatusCount = 6;

}  // namespace modd::link::backfill

// Event subscriptions, ON_CHANGE and THRESHOLD (docs/planning.md, "Event subscriptions"): their
// codes and bounds; the definition is modd_contracts.events, its vectors
// contracts/vectors/events.json.
namespace modd::link::events {

// Most events one window of an event subscription carries (its declared or derived 'at most
// N'): the link's list bound.
inline constexpr uint32_t kMaxEvents = 65535;

// What makes an event.
enum class EventKind : uint8_t {
  OnChange = 0,  // the sample differs from the last reported one by more than the deadband
  Threshold = 1,  // the sample crosses the level by more than the hysteresis
};
// The number of EventKind values.
inline constexpr size_t kEventKindCount = 2;

// How an ON_CHANGE deadband is read.
enum class DeadbandMode : uint8_t {
  Absolute = 0,  // in the topic's unit: |x - last| > deadband
  Relative = 1,  // a fraction of the last reported value: |x - last| > deadband * |last|
};
// The number of DeadbandMode values.
inline constexpr size_t kDeadbandModeCount = 2;

// Which crossings of a THRESHOLD are events (a bit set).
enum class Crossing : uint8_t {
  Up = 1,  // below to above: x > level + hysteresis
  Down = 2,  // above to below: x < level - hysteresis
  Both = 3,  // either
};
// The number of Crossing values.
inline constexpr size_t kCrossingCount = 3;

}  // namespace modd::link::events

// Datagram form of the link (docs/protocol.md, "Datagram transports").
namespace modd::link::dgram {

// DATA datagram of consecutive slots.
inline constexpr uint8_t kData = 0x30;
// DATA datagram with a presence bitmap.
inline constexpr uint8_t kDataBitmap = 0x31;
// A piece of a slot too large for one datagram.
inline constexpr uint8_t kFragment = 0x32;
// Control datagram: one tagged link frame.
inline constexpr uint8_t kControl = 0x40;
// Handshake datagram (untagged).
inline constexpr uint8_t kHandshake = 0x41;
// A piece of a control frame too large for one datagram.
inline constexpr uint8_t kControlFragment = 0x42;
// Control frame type: ranges of slots to resend.
inline constexpr uint8_t kNack = 0x09;
// Most ranges of one NACK (the fewest is 1).
inline constexpr size_t kMaxNackRanges = 32;
// Most slots of one NACK range (the fewest is 1).
inline constexpr uint64_t kMaxNackRangeSlots = 65535;
// Most slots of one DATA datagram (its slot count is one byte).
inline constexpr size_t kMaxDatagramSlots = 255;
// Most fragments of one slot.
inline constexpr size_t kMaxFragments = 16;
// Bytes before a fragment's piece: type, config id, slot16, fragment byte.
inline constexpr size_t kFragmentHead = 5;
// Truncated HMAC tag of a DATA datagram, in bytes.
inline constexpr size_t kTag = 4;
// Truncated HMAC tag of a control datagram, in bytes.
inline constexpr size_t kControlTag = 8;
// Smallest packet a radio may carry (link.maxPacket), in bytes.
inline constexpr uint32_t kMinPacket = 32;
// Largest packet (link.maxPacket): the largest UDP payload, in bytes.
inline constexpr uint32_t kMaxPacket = 65507;
// The packet of a udp link when the model gives none: Ethernet's MTU less the IP and UDP
// headers.
inline constexpr uint32_t kDefaultUdpPacket = 1472;
// The packet of a serial link when the model gives none (a SiK radio's frame).
inline constexpr uint32_t kDefaultSerialPacket = 252;

}  // namespace modd::link::dgram
