// The PubBroker's counters, in the order STATUS carries them (docs/protocol.md).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace modd::broker {

// Why a record was refused. The numbers are also the REJECT reason codes of the ingress
// protocol (docs/ingress.md); keep them stable.
enum class Reject : uint8_t {
  UnknownTopic,
  WrongType,
  NotFinite,
  Timestamp,
  Overflow,
  Malformed,
  Quota,
  kCount
};
const char* reject_name(Reject r);

struct Counters {
  uint64_t samples_in = 0;  // records received (accepted + rejected)
  uint64_t accepted = 0;
  uint64_t rejected[static_cast<int>(Reject::kCount)] = {};
  uint64_t ingress_malformed_frames = 0;
  uint64_t publishers_connected = 0;
  uint64_t publishers_total = 0;
  uint64_t link_bytes_sent = 0;
  uint64_t auth_failures = 0;
  uint64_t link_sessions = 0;
  uint64_t& rej(Reject r) { return rejected[static_cast<int>(r)]; }
  uint64_t rejected_total() const {
    uint64_t n = 0;
    for (uint64_t r : rejected) n += r;
    return n;
  }
};

// The STATUS counter list (index = position on the wire; fields are only ever appended).
enum StatusField : uint8_t {
  kUptimeS,
  kSamplesIn,
  kSamplesArchived,
  kRejUnknownTopic,
  kRejWrongType,
  kRejNotFinite,
  kRejTimestamp,
  kRejOverflow,
  kRejMalformed,
  kArchiveFailed,
  kIngressMalformedFrames,
  kPublishersConnected,
  kFramesSent,
  kFramesDropped,
  kLinkBytesSent,
  kDiskFreeMb,
  kBufferFillPct,
  kArchiveFiles,
  kAuthFailures,
  kConfigId,
  kRejQuota,
  kArchiveState,
  kArchiveRateBps,
  kSamplesPending,
  kDgramSent,
  kDgramResent,
  kDgramNacks,
  kDgramDropped,
  kDgramForged,
  kDgramReplayed,
  kStatusFieldCount
};

// What a datagram link (udp, serial) reports in STATUS: datagrams sent (fragments and
// resends included), datagrams resent for NACKs, NACKs received, slots not sent (no session,
// or too large for 16 fragments), forged and replayed datagrams received (dropped).
struct LinkDatagramCounts {
  uint64_t sent = 0, resent = 0, nacks = 0, dropped = 0, forged = 0, replayed = 0;
};

// STATUS archive_state values.
enum ArchiveStateCode : uint8_t { kArchiveOk = 0, kArchiveLowSpace = 1, kArchiveDiskFull = 2 };
extern const char* const kStatusFieldNames[kStatusFieldCount];

}  // namespace modd::broker
