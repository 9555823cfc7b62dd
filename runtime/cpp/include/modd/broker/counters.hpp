// The PubBroker's counters, in the order STATUS carries them (docs/protocol.md).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace modd::broker {

enum class Reject : uint8_t { UnknownTopic, WrongType, NotFinite, Backwards, Overflow, Malformed, kCount };
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

// The STATUS counter list, version 1 (index = position on the wire).
enum StatusField : uint8_t {
  kUptimeS, kSamplesIn, kSamplesArchived, kRejUnknownTopic, kRejWrongType, kRejNotFinite, kRejBackwards,
  kRejOverflow, kRejMalformed, kArchiveFailed, kIngressMalformedFrames, kPublishersConnected, kFramesSent,
  kFramesDropped, kLinkBytesSent, kDiskFreeMb, kBufferFillPct, kArchiveFiles, kAuthFailures, kConfigId,
  kStatusFieldCount
};
extern const char* const kStatusFieldNames[kStatusFieldCount];

}  // namespace modd::broker
