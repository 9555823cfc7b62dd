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

}  // namespace modd::broker
