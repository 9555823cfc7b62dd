// The PubBroker's counters, in the order STATUS carries them (docs/protocol.md).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "modd/ingress/wire.gen.hpp"
#include "modd/link/wire.gen.hpp"

namespace modd::broker {

// Why a record was refused: the REJECT reason codes of the ingress protocol and the
// index of the rejected_* counters (generated from wire.json: ingress/wire.gen.hpp).
using ingress::Reject;
// The result of validating a record that was accepted (one past the last reason).
inline constexpr Reject kAccepted = static_cast<Reject>(ingress::kRejectCount);
inline const char* reject_name(Reject r) {
  auto i = static_cast<size_t>(r);
  return i < ingress::kRejectCount ? ingress::kRejectLabels[i] : "?";
}

struct Counters {
  uint64_t samples_in = 0;  // records received (accepted + rejected)
  uint64_t accepted = 0;
  uint64_t rejected[ingress::kRejectCount] = {};
  uint64_t ingress_malformed_frames = 0;
  uint64_t publishers_connected = 0;
  uint64_t publishers_total = 0;
  uint64_t link_bytes_sent = 0;
  uint64_t auth_failures = 0;
  uint64_t link_sessions = 0;
  uint64_t health_corrected = 0;  // HEALTH names and fields made safe at the ingress
  uint64_t status_coalesced = 0;  // changes that shared a STATUS with an earlier one
  uint64_t& rej(Reject r) { return rejected[static_cast<int>(r)]; }
  uint64_t rejected_total() const {
    uint64_t n = 0;
    for (uint64_t r : rejected) n += r;
    return n;
  }
};

// The STATUS counter list (index = position on the wire; fields are only ever appended):
// link::StatusField, generated from wire.json (link/wire.gen.hpp) for both codecs.
using link::kStatusFieldCount;
using link::kStatusFieldLabels;
using link::StatusField;
constexpr size_t at(StatusField f) { return static_cast<size_t>(f); }

// What a datagram link (udp, serial) reports in STATUS: datagrams sent (fragments and
// resends included), datagrams resent for NACKs, NACKs received, slots not sent (no session,
// or too large for 16 fragments), forged and replayed datagrams received (dropped).
struct LinkDatagramCounts {
  uint64_t sent = 0, resent = 0, nacks = 0, dropped = 0, forged = 0, replayed = 0;
};

// STATUS archive_state values.
enum ArchiveStateCode : uint8_t { kArchiveOk = 0, kArchiveLowSpace = 1, kArchiveDiskFull = 2 };

}  // namespace modd::broker
