#include "modd/broker/executor.hpp"

#include "modd/link/codec.hpp"
#include "modd/util/error.hpp"

namespace modd::broker {

std::unique_ptr<Executor::Active> Executor::build(const link::Config& cfg,
                                                  const std::vector<uint32_t>& globals,
                                                  int64_t epoch) {
  auto a = std::make_unique<Active>();
  a->config_id = cfg.config_id;
  a->epoch = epoch;
  std::vector<uint64_t> periods;
  for (uint32_t id = 0; id < cfg.streams.size(); ++id) {
    const auto& s = cfg.streams[id];
    if (s.topic >= cfg.topics.size() || s.topic >= globals.size())
      throw Error(ErrorCode::BadConfig, "stream " + std::to_string(id) + " names a missing topic");
    link::ValueType type = cfg.topics[s.topic].type;
    a->acc.emplace_back(type, s.aggregation, s.percentile);
    a->events.push_back(link::is_event(s.aggregation)
                            ? std::make_unique<EventDetector>(event_spec(s.aggregation, s.event))
                            : nullptr);
    a->periods_us.push_back(s.period_us);
    a->kinds.push_back(
        link::value_kind(type, s.aggregation, cfg.resolutions.empty() ? 0 : cfg.resolutions[id]));
    uint32_t g = globals[s.topic];
    if (a->by_topic.size() <= g) a->by_topic.resize(g + 1);
    a->by_topic[g].push_back(id);
    periods.push_back(s.period_us);
  }
  a->slots = std::make_unique<link::SlotIterator>(periods);
  a->next_due =
      a->slots->empty() ? kNever : epoch + static_cast<int64_t>(a->slots->peek_offset_us()) * 1000;
  return a;
}

std::optional<int64_t> Executor::apply(const link::Config& cfg,
                                       const std::vector<uint32_t>& globals, int64_t now) {
  if (pending_) return std::nullopt;
  if (!active_ || active_->next_due == kNever) {
    active_ = build(cfg, globals, now);
    need_sync_ = true;
    return now;
  }
  switch_at_ = active_->next_due;
  pending_ = build(cfg, globals, switch_at_);
  return switch_at_;
}

int64_t Executor::next_due_ns() const { return active_ ? active_->next_due : kNever; }

void Executor::on_sample(uint32_t g, double number, int64_t integer, int64_t t_ns) {
  if (!active_ || g >= active_->by_topic.size()) return;
  for (uint32_t id : active_->by_topic[g]) {
    if (auto& det = active_->events[id]) {
      bool is_float = active_->kinds[id].scalar == link::ScalarKind::F32 ||
                      active_->kinds[id].scalar == link::ScalarKind::F64;
      det->add(t_ns, is_float ? number : static_cast<double>(integer));
    } else {
      active_->acc[id].add(number, integer);
    }
  }
}

// An event stream's window [date - P, date): its events, times after the window's start.
link::Value Executor::take_events(Active& a, uint32_t id, int64_t date) {
  EventWindow w = a.events[id]->take();
  int64_t start = date - static_cast<int64_t>(a.periods_us[id]) * 1000;
  bool is_float =
      a.kinds[id].scalar == link::ScalarKind::F32 || a.kinds[id].scalar == link::ScalarKind::F64;
  link::Value v = event_value(w, start, is_float);
  counters_.events_coalesced += w.coalesced;
  return v;
}

void Executor::advance(int64_t t, FrameSink& sink) {
  while (active_ && active_->next_due <= t) {
    int64_t date = active_->next_due;
    fire(sink);
    if (pending_ && date >= switch_at_) {
      active_ = std::move(pending_);
      switch_at_ = kNever;
      need_sync_ = true;
    }
  }
}

void Executor::fire_slot(FrameSink& sink, const link::Data& d,
                         const std::vector<link::ValueKind>& kinds,
                         const std::vector<uint32_t>& streams, int64_t date) {
  // The values as a DATA frame lays them out, without the frame's header (length, type,
  // seq8) and bitmap: the datagram carries its own header and one bitmap for all its slots.
  link::Data body = d;
  body.sync = false;
  std::vector<uint8_t> frame;
  link::encode_data(frame, body, kinds);
  std::vector<bool> presence;
  bool all = true;
  for (const auto& v : d.values) {
    presence.push_back(v.present);
    all = all && v.present;
  }
  size_t len_bytes = 1;
  while (frame[len_bytes - 1] & 0x80) ++len_bytes;
  size_t skip = len_bytes + 2 + (all ? 0 : (d.values.size() + 7) / 8);
  std::vector<uint8_t> values(frame.begin() + static_cast<std::ptrdiff_t>(skip), frame.end());
  // Quantised streams are written against the datagram the slot joins (its chain).
  link::SlotEncoder enc;
  bool quantised = false;
  for (const auto& k : kinds) quantised = quantised || k.resolution > 0;
  if (quantised)
    enc = [vals = d.values, kinds, streams](link::Chain& chain) {
      std::vector<uint8_t> out;
      link::encode_slot_values(out, vals, kinds, streams, chain);
      return out;
    };
  if (sink.send_slot(d.config_id, d.slot, date, std::move(values), std::move(presence),
                     std::move(enc))) {
    ++counters_.frames_sent;
    need_sync_ = false;
  } else {
    ++counters_.frames_dropped;
  }
}

void Executor::fire(FrameSink& sink) {
  Active& a = *active_;
  int64_t date = a.next_due;
  link::Slot slot = a.slots->next();
  a.next_due = a.epoch + static_cast<int64_t>(a.slots->peek_offset_us()) * 1000;
  ++counters_.slots_fired;
  link::Data d;
  d.sync = need_sync_;
  d.config_id = a.config_id;
  d.slot = slot.index;
  d.seq8 = static_cast<uint8_t>(slot.index & 0xFF);
  std::vector<link::ValueKind> kinds;
  kinds.reserve(slot.streams.size());
  bool any = false;
  for (uint32_t id : slot.streams) {
    d.values.push_back(a.events[id] ? take_events(a, id, date) : a.acc[id].take());
    kinds.push_back(a.kinds[id]);
    any = any || d.values.back().present;
  }
  if (sink.wants_slots()) {
    if (!any) ++counters_.slots_empty;
    fire_slot(sink, d, kinds, slot.streams, date);
    return;
  }
  if (!any) {
    ++counters_.slots_empty;
    need_sync_ = true;  // the receiver sees a gap: the next frame says where it is
    return;
  }
  std::vector<uint8_t> frame;
  link::encode_data(frame, d, kinds);
  if (sink.send_data(std::move(frame))) {
    ++counters_.frames_sent;
    need_sync_ = false;
  } else {
    ++counters_.frames_dropped;
    need_sync_ = true;
  }
}

}  // namespace modd::broker
