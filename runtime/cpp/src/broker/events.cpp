#include "modd/broker/events.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace modd::broker {

namespace ev = link::events;

EventDetector::EventDetector(const EventSpec& spec) : spec_(spec) {
  if (spec.max_events < 1 || spec.max_events > ev::kMaxEvents)
    throw std::invalid_argument("at most N events: N out of 1.." + std::to_string(ev::kMaxEvents));
  if (!(spec.deadband >= 0) || !(spec.hysteresis >= 0))  // NaN too
    throw std::invalid_argument("a deadband or hysteresis is a number >= 0");
  window_.events.reserve(spec.max_events < 64 ? spec.max_events : 64);
}

bool EventDetector::is_event(double x) {
  if (spec_.kind == ev::EventKind::OnChange) {
    if (last_) {
      double band = spec_.mode == ev::DeadbandMode::Relative ? spec_.deadband * std::fabs(*last_)
                                                             : spec_.deadband;
      if (!(std::fabs(x - *last_) > band)) return false;
    }
    last_ = x;
    return true;
  }
  if (!above_) {
    above_ = x > spec_.level;
    return false;
  }
  ev::Crossing crossing;
  if (!*above_ && x > spec_.level + spec_.hysteresis) {
    above_ = true;
    crossing = ev::Crossing::Up;
  } else if (*above_ && x < spec_.level - spec_.hysteresis) {
    above_ = false;
    crossing = ev::Crossing::Down;
  } else {
    return false;
  }
  return (static_cast<uint8_t>(spec_.crossing) & static_cast<uint8_t>(crossing)) != 0;
}

bool EventDetector::add(int64_t t_ns, double x) {
  if (!is_event(x)) return false;
  if (window_.events.size() < spec_.max_events) {
    window_.events.push_back({t_ns, x});
  } else {
    window_.events.back() = {t_ns, x};
    ++window_.coalesced;
    ++coalesced_total_;
  }
  return true;
}

EventWindow EventDetector::take() {
  EventWindow out = std::move(window_);
  window_ = EventWindow{};
  return out;
}

EventSpec event_spec(link::Aggregation a, const link::EventParams& p) {
  EventSpec spec;
  bool on_change = a == link::Aggregation::OnChange;
  spec.kind = on_change ? ev::EventKind::OnChange : ev::EventKind::Threshold;
  spec.max_events = p.max_events ? p.max_events : ev::kMaxEvents;
  spec.deadband = p.deadband;
  spec.level = p.level;
  spec.hysteresis = p.hysteresis;
  if (on_change)
    spec.mode = static_cast<ev::DeadbandMode>(p.code);
  else
    spec.crossing = static_cast<ev::Crossing>(p.code);
  return spec;
}

link::Value event_value(const EventWindow& w, int64_t start_ns, bool is_float) {
  link::Value v;
  v.present = !w.events.empty();
  for (const Event& e : w.events) {
    v.times_us.push_back(e.t_ns > start_ns ? static_cast<uint64_t>(e.t_ns - start_ns) / 1000 : 0);
    if (is_float)
      v.numbers.push_back(e.value);
    else
      v.integers.push_back(static_cast<int64_t>(e.value));
  }
  v.coalesced = w.coalesced;
  return v;
}

}  // namespace modd::broker
