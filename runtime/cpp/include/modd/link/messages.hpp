// Messages of the MoDD link protocol (docs/protocol.md), apart from the codec.
#pragma once
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "modd/link/aggregation_table.gen.hpp"  // the Aggregation enum, generated
#include "modd/link/wire.gen.hpp"               // versions, limits, MsgType, ValueType (wire.json)

namespace modd::link {

const char* value_type_name(ValueType t);
const char* aggregation_name(Aggregation a);
bool parse_value_type(const std::string& s, ValueType& out);
bool parse_aggregation(const std::string& s, Aggregation& out);

using Nonce = std::array<uint8_t, 16>;
using Mac = std::array<uint8_t, 32>;

struct Hello {
  uint8_t version = kVersion;
  Nonce nonce{};
};
struct Challenge {
  uint8_t version = kVersion;
  Nonce nonce{};
};
struct Auth {
  Mac mac{};
};
struct AuthOk {
  Mac mac{};
  uint8_t config_id = 0;
  uint64_t epoch_ns = 0;
};
struct Ping {
  std::vector<uint8_t> payload;
};
struct Pong {
  std::vector<uint8_t> payload;
};

struct TopicSpec {
  std::string name;
  ValueType type = ValueType::Float32;
  uint32_t buffer_size = 1;
  uint64_t period_us = 0;  // publication period, informative (0 = unknown)
};
// ON_CHANGE's and THRESHOLD's parameters, after the stream's period in CONFIG
// (docs/protocol.md, "CONFIG"; their meaning: broker/events.hpp).
struct EventParams {
  uint8_t code = 0;         // ON_CHANGE: events::DeadbandMode; THRESHOLD: events::Crossing
  double deadband = 0;      // ON_CHANGE (a fraction of the last event's value when relative)
  double level = 0;         // THRESHOLD
  double hysteresis = 0;    // THRESHOLD
  uint32_t max_events = 0;  // N, the declared worst case; 0: derived (every sample)
  bool operator==(const EventParams&) const = default;
};
inline bool is_event(Aggregation a) {
  return a == Aggregation::OnChange || a == Aggregation::Threshold;
}
struct StreamSpec {
  uint32_t topic = 0;  // index into Config::topics
  Aggregation aggregation = Aggregation::Min;
  uint64_t period_us = 0;  // window period, > 0
  double percentile = 0;   // PERCENTILE's p (0..100), f64le after the period; else unused
  EventParams event;       // ON_CHANGE, THRESHOLD; else unused
};
struct Config {
  uint8_t config_id = 1;
  uint32_t status_period_s = 0;  // 0: no STATUS
  std::vector<TopicSpec> topics;
  std::vector<StreamSpec> streams;  // the sent streams, in stream-id order
  // Optional trailing field (datagram links): the accepted delay the PubBroker packs
  // slots with; absent = the delay of its config file (docs/protocol.md, "CONFIG").
  std::optional<uint32_t> accepted_delay_ms;
  // Optional trailing field after the delay: each stream's declared resolution (0 =
  // none); empty when no stream declares one (docs/protocol.md, "Quantised values").
  std::vector<double> resolutions;
  bool operator==(const Config&) const = default;
};
inline bool operator==(const TopicSpec& a, const TopicSpec& b) {
  return a.name == b.name && a.type == b.type && a.buffer_size == b.buffer_size &&
         a.period_us == b.period_us;
}
inline bool operator==(const StreamSpec& a, const StreamSpec& b) {
  return a.topic == b.topic && a.aggregation == b.aggregation && a.period_us == b.period_us &&
         a.percentile == b.percentile && a.event == b.event;
}

struct ConfigAck {
  uint8_t config_id = 0;
  uint8_t status = 0;
  uint64_t epoch_ns = 0;
};
// The on-board part of a deployed model (docs/protocol.md, "ONBOARD"): `model` is one
// zstd frame of the model file's bytes (at most kMaxOnboardWire, kMaxOnboardBytes once
// decompressed), for modd-sensors and modd-mavlink --watch.
struct Onboard {
  uint8_t config_id = 0;
  std::vector<uint8_t> model;
};
// What each on-board process did with it: `answers` is one zstd frame of a JSON object
// by process name; status 0 when the model file was written.
struct OnboardAck {
  uint8_t config_id = 0;
  uint8_t status = 0;
  std::vector<uint8_t> answers;
};
// One plug-and-play instrument's health (docs/protocol.md, "STATUS"; fields in the order
// of the table there), as modd-sensors reports it through the ingress (HEALTH) and the
// PubBroker forwards it in STATUS.
struct SensorHealth {
  std::string name;
  std::vector<uint64_t> fields;
  bool operator==(const SensorHealth&) const = default;
};
// kMaxHealthSensors, kMaxHealthFields, kMaxHealthName: wire.gen.hpp (contract wire.json)
// `sensors` travel after the counters, only when there is one (older frames are unchanged).
struct Status {
  std::vector<uint64_t> counters;
  std::vector<SensorHealth> sensors = {};
};
struct ErrorMsg {
  uint8_t code = 0;
  std::string message;
};

// One stream's value in a DATA frame. Which fields are used depends on the
// stream's ValueKind (see value_kind()).
struct Value {
  bool present = false;
  double number = 0;              // F32, F64, and the mean of AVERAGE
  int64_t integer = 0;            // ZigZag and Bool kinds
  uint64_t count = 0;             // AVERAGE sample count, COUNT
  std::vector<double> numbers;    // ALL of float topics
  std::vector<int64_t> integers;  // ALL of int/bool topics
  // An event window (ON_CHANGE, THRESHOLD): each event's value in numbers or integers, its
  // time in µs after the window's start, and the events coalesced beyond N.
  std::vector<uint64_t> times_us;
  uint64_t coalesced = 0;
};

struct Data {
  bool sync = false;          // types 0x12/0x13: config id and full slot number
  uint8_t config_id = 0;      // only on the wire when sync
  uint64_t slot = 0;          // full slot number (only on the wire when sync)
  uint8_t seq8 = 0;           // slot mod 256 (on the wire when !sync)
  std::vector<Value> values;  // one per stream due in the slot, stream-id order
};

using Message = std::variant<Hello, Challenge, Auth, AuthOk, Ping, Pong, Config, ConfigAck, Onboard,
                             OnboardAck, Status, ErrorMsg>;

// How a (topic type, aggregation) pair is written in DATA.
enum class ScalarKind : uint8_t { F32, F64, ZigZag, Bool, UVarint };
struct ValueKind {
  Aggregation aggregation;
  ScalarKind scalar;      // the value, or each element of ALL; UVarint for COUNT
  double resolution = 0;  // > 0: float values go as integer steps (link/quantise.hpp)
};
// resolution is kept for F32/F64 values only (the others are exact already).
ValueKind value_kind(ValueType type, Aggregation aggregation, double resolution = 0);

}  // namespace modd::link
