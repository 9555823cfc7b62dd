// Instruments' health as the PubBroker accepts it at the ingress (HEALTH, docs/ingress.md)
// and lists it in STATUS (docs/protocol.md, "Instruments' health"): names made printable,
// numbers brought into range, and a STATUS that fits its room, the rest counted.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "modd/link/messages.hpp"
#include "modd/link/wire.gen.hpp"

namespace modd::broker {

// Largest count a health field keeps (2^53 − 1, exact in a double: the operator's tools) and
// latest `last_value_ms` (2100-01-01; a later one reads as 0, none): contract wire.json.
using link::kMaxHealthCount;
using link::kMaxLastValueMs;
inline constexpr size_t kStateField = 0, kLastValueField = 4;
inline constexpr uint64_t kStateClosed = 0, kStateOpen = 1, kStateSilent = 2;

// `raw` with each byte that is not part of valid UTF-8, and each control character (C0,
// DEL, C1, line and paragraph separators, bidirectional overrides), replaced by '?': no
// escape sequence reaches the operator and the name never grows.
std::string printable_name(std::string_view raw);

// Makes one instrument's health safe to forward: a printable name, `state` beyond 2 read as
// 2 (silent), `last_value_ms` beyond kMaxLastValueMs read as 0, every other field at most
// kMaxHealthCount. Returns how many corrections it made (0: the report was fine).
size_t sanitise_health(link::SensorHealth& h);

// Bytes `h` takes in STATUS's list.
size_t health_entry_size(const link::SensorHealth& h);

// Sets the INSTRUMENTS, INSTRUMENTS_OPEN, _SILENT and _CLOSED counters of `all`.
void count_instruments(std::vector<uint64_t>& counters, const std::vector<link::SensorHealth>& all);

// The STATUS of `counters` and of as many of `all` as fit `room` bytes as a whole link frame
// (closed and silent instruments first, then open ones, each by name; the list sorted by
// name). The INSTRUMENTS_* counters summarise every instrument, listed or not, so none is
// dropped unsaid. Larger than `room` only when the counters alone are.
link::Status fit_status(std::vector<uint64_t> counters, std::vector<link::SensorHealth> all,
                        size_t room);

}  // namespace modd::broker
