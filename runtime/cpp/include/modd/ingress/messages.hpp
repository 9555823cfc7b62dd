// Messages of the local ingress protocol (docs/ingress.md): a publisher says
// hello, registers topic names once with a local id and a type, then sends
// batches of (local id, publisher timestamp, value) records.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "modd/ingress/wire.hpp"
#include "modd/link/messages.hpp"

namespace modd::ingress {

using link::ValueType;
// kVersion, kMinVersion, kMaxFrame and MsgType: modd/ingress/wire.hpp (shared with the client).

struct Hello {
  uint8_t version = kVersion;
  std::string publisher;
};

// The drone's topics and the timestamp bounds, so that a client refuses at the call what
// the broker would refuse. Sent after HELLO and again whenever the topics change.
struct CatalogueTopic {
  std::string name;
  ValueType type = ValueType::Float32;
};
struct Catalogue {
  std::string drone;
  uint64_t max_future_ms = 0, max_past_ms = 0;  // 0: no bound
  bool accept_unknown = false;
  std::vector<CatalogueTopic> topics;
};

// Cumulative counts of this connection's records, sent after each archive flush:
// `received` records decoded; every record before `settled` is either refused (and told in a
// REJECT) or in the archive file (fsynced with fsync "chunk"); `archived` of them are on disk.
struct Ack {
  uint64_t received = 0, settled = 0, archived = 0;
};

// `count` records of `local_id` refused for `reason` (the broker's Reject code) since the
// previous REJECT for them; `detail` says why in words (the first case of the batch).
struct RejectMsg {
  uint32_t local_id = 0;
  uint8_t reason = 0;
  uint64_t count = 0;
  std::string detail;
};
struct Register {
  uint32_t local_id = 0;
  ValueType type = ValueType::Float32;
  std::string topic;
};

// One record of a SAMPLES batch. Ints and bools travel in `integer`.
struct Record {
  uint32_t local_id = 0;
  int64_t timestamp_ns = 0;
  double number = 0;
  int64_t integer = 0;
};

}  // namespace modd::ingress
