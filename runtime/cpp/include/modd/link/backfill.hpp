// Backfill frames of the link protocol (docs/protocol.md, "Backfill"): messages
// and their codec. The base station asks for the windows of one topic and
// aggregation over a past time range; the PubBroker answers from its archive
// with BACKFILL_DATA, BACKFILL_PROGRESS and one BACKFILL_END. Decoders throw
// modd::Error(BadFrame) with the byte offset in the frame body.
#pragma once
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "modd/link/codec.hpp"
#include "modd/link/messages.hpp"

namespace modd::link::backfill {

// Type, EndStatus, kMaxWindows and kMaxBatch: modd/link/wire.gen.hpp (wire.json).

// Windows [from_ns + k·P, from_ns + (k+1)·P) for k = resume .. windows-1.
struct Request {
  uint64_t request_id = 0;
  std::string topic;
  ValueType type = ValueType::Float32;
  Aggregation aggregation = Aggregation::Min;
  uint64_t period_us = 0;
  double percentile = 0;  // PERCENTILE's p (f64le after the period); else unused
  // ON_CHANGE, THRESHOLD: the parameters (as CONFIG writes them) and the date the
  // detector's state starts from (the config's epoch, u64le), after the period; the
  // PubBroker replays the archive from there to the first window asked (docs/protocol.md,
  // "Backfill of events"). Else unused.
  EventParams event;
  uint64_t state_from_ns = 0;
  uint64_t from_ns = 0;
  uint64_t windows = 0;
  uint64_t resume = 0;
  uint64_t rate_bps = 0;  // 0: the broker's default pace
  int64_t window_start_ns(uint64_t k) const {
    return static_cast<int64_t>(from_ns + k * period_us * 1000);
  }
  bool operator==(const Request&) const = default;
};
struct DataFrame {
  uint64_t request_id = 0;
  uint64_t first = 0;
  std::vector<Value> values;  // windows first .., absent: no sample in the window
};
struct Progress {
  uint64_t request_id = 0, next = 0, windows = 0, bytes_sent = 0, rate_bps = 0;
  bool operator==(const Progress&) const = default;
};
struct End {
  uint64_t request_id = 0;
  EndStatus status = EndStatus::Done;
  uint64_t next = 0;
  std::string message;
  bool operator==(const End&) const = default;
};
struct Cancel {
  uint64_t request_id = 0;
  bool operator==(const Cancel&) const = default;
};
using Message = std::variant<Request, Progress, End, Cancel>;

bool is_backfill_type(uint8_t type);
void encode(std::vector<uint8_t>& out, const Message& m);  // any but DATA
void encode_data(std::vector<uint8_t>& out, const DataFrame& d, const ValueKind& kind);
Message decode(const RawFrame& f);            // any but DATA
uint64_t data_request_id(const RawFrame& f);  // which request (so which kind)
DataFrame decode_data(const RawFrame& f, const ValueKind& kind);

}  // namespace modd::link::backfill
