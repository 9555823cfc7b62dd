// Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit.
// The delivered value's field names and version
// (metamodel/src/modd_contracts/schemas/delivered_value.schema.json),
// read by the C++ subscriber client's parser (docs/subbroker.md).
#pragma once

#include <cstdint>
#include <string_view>

namespace modd::delivered_value {

// Payload version; a reader rejects a higher one.
inline constexpr int64_t kVersion = 1;

// The subscription's name (also the last chunk of the key).
inline constexpr std::string_view kSubscriber = "subscriber";
// The topic, drone.sensor.variable.
inline constexpr std::string_view kTopic = "topic";
// How the window's samples were reduced (the metamodel's Aggregation).
inline constexpr std::string_view kAggregation = "aggregation";
// The subscription's period, an exact decimal string.
inline constexpr std::string_view kPeriodS = "period_s";
// The variable's unit (the metamodel's Unit).
inline constexpr std::string_view kUnit = "unit";
// The running configuration the window belongs to.
inline constexpr std::string_view kConfigId = "config_id";
// The schedule slot of the DATA frame that closed the window.
inline constexpr std::string_view kSlot = "slot";
// Start of the window [start_ns, end_ns), ns since the Unix epoch on the drone's clock.
inline constexpr std::string_view kStartNs = "start_ns";
// End of the window (exclusive), ns since the Unix epoch on the drone's clock.
inline constexpr std::string_view kEndNs = "end_ns";
// The window's value: a number or boolean, the list of raw samples for ALL, or null when the window had no sample.
inline constexpr std::string_view kValue = "value";
// Samples behind the value when the aggregation carries it (AVERAGE, COUNT, ALL), else null.
inline constexpr std::string_view kCount = "count";
// When the SubBroker delivered it, ns since the Unix epoch on the base station's clock.
inline constexpr std::string_view kDeliveredNs = "delivered_ns";
// Payload version; a reader rejects a higher one.
inline constexpr std::string_view kV = "v";
// Present and true when the window was recomputed from the drone's archive after the link missed it (backfill); absent on live values.
inline constexpr std::string_view kBackfilled = "backfilled";
// The window's identity, first part: the drone whose window it is.
inline constexpr std::string_view kDrone = "drone";
// The window's identity: the epoch of the configuration it belongs to (the PubBroker's CONFIG_ACK), ns since the Unix epoch on the drone's clock.
inline constexpr std::string_view kEpochNs = "epoch_ns";
// The window's identity: its index k on the configuration's grid, the window being [epoch_ns + k period, epoch_ns + (k + 1) period).
inline constexpr std::string_view kWindow = "window";
// An event subscription's window (ON_CHANGE, THRESHOLD: value is the list of its events' values): each event's sample time, ns since the Unix epoch on the drone's clock (the PubBroker's stamp of the sample, to the microsecond), in value's order; absent for the other aggregations.
inline constexpr std::string_view kEventNs = "event_ns";
// An event window: how many events beyond the subscription's worst case (at most N a window) were coalesced into its last event (value's last item is the window's newest event); count is then the window's events, len(value) + coalesced.
inline constexpr std::string_view kCoalesced = "coalesced";

}  // namespace modd::delivered_value
