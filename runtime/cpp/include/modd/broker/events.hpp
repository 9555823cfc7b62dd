// Event subscriptions, ON_CHANGE and THRESHOLD: the detector of one event stream
// (docs/planning.md, "Event subscriptions"; the reference definition is
// modd_contracts.events, its vectors contracts/vectors/events.json). Its state
// (ON_CHANGE's last event value, THRESHOLD's side) carries from window to window;
// each window keeps at most N events: beyond, the newest replaces the last kept one
// and `coalesced` counts it, so no event is dropped silently. Memory: N events.
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "modd/link/messages.hpp"
#include "modd/link/wire.gen.hpp"

namespace modd::broker {

struct EventSpec {
  link::events::EventKind kind = link::events::EventKind::OnChange;
  uint32_t max_events = 1;  // N, 1..kMaxEvents
  double deadband = 0;      // ON_CHANGE, >= 0
  link::events::DeadbandMode mode = link::events::DeadbandMode::Absolute;
  double level = 0;       // THRESHOLD
  double hysteresis = 0;  // THRESHOLD, >= 0
  link::events::Crossing crossing = link::events::Crossing::Both;
};

struct Event {
  int64_t t_ns = 0;  // the sample's time
  double value = 0;  // the sample (an int topic's as a double, exact to 2^53)
  bool operator==(const Event&) const = default;
};

struct EventWindow {
  std::vector<Event> events;  // at most N, in time order
  uint64_t coalesced = 0;     // events replaced by a newer one beyond N
};

class EventDetector {
 public:
  // Throws std::invalid_argument for N outside 1..kMaxEvents or a negative (or NaN)
  // deadband or hysteresis.
  explicit EventDetector(const EventSpec& spec);
  // One sample, in time order: returns whether it is an event (kept in the window).
  bool add(int64_t t_ns, double x);
  // The window's events, and a new empty window (the detector's state stays).
  EventWindow take();
  uint64_t coalesced_total() const { return coalesced_total_; }

 private:
  bool is_event(double x);
  EventSpec spec_;
  std::optional<double> last_;  // ON_CHANGE
  std::optional<bool> above_;   // THRESHOLD
  EventWindow window_;
  uint64_t coalesced_total_ = 0;
};

// The detector's definition of an event stream as CONFIG or BACKFILL_REQUEST carries it
// (N = 0, derived: kMaxEvents).
EventSpec event_spec(link::Aggregation a, const link::EventParams& p);
// A window [start_ns, start_ns + P)'s events as the link carries them: each time in µs
// after the window's start, the values as doubles (float topics) or integers.
link::Value event_value(const EventWindow& w, int64_t start_ns, bool is_float);

}  // namespace modd::broker
