// The schedule executor: owns the running config's accumulators and slot
// iterator, and emits one DATA frame per due slot. Time is passed in (broker
// stamps on its timeline, util/clock.hpp: monotonic, never stepped), so a test
// drives it with a fake clock.
//
// Contract (docs/protocol.md, "Windows"): slot k of a config with epoch E is
// due at E + offset_k; a window [E+(j-1)P, E+jP) aggregates exactly the
// samples stamped inside it, because the broker calls advance(t) before it
// ingests a sample stamped t, and a timer calls advance(now) when idle.
// A new CONFIG takes effect at the running config's next slot date (its
// epoch), so no sample is lost or counted twice.
#pragma once
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "modd/broker/accumulator.hpp"
#include "modd/broker/events.hpp"
#include "modd/link/messages.hpp"
#include "modd/link/quantise.hpp"
#include "modd/link/schedule.hpp"

namespace modd::broker {

class FrameSink {
 public:
  virtual ~FrameSink() = default;
  // One whole DATA frame; returns false if it could not be sent (no link, backlog).
  virtual bool send_data(std::vector<uint8_t>&& frame) = 0;
  // Datagram transports (udp, serial) take every slot, empty ones included, as its
  // encoded values and presence flags (send_slot), instead of DATA frames.
  virtual bool wants_slots() const { return false; }
  // enc, set when the slot has quantised streams, writes its values against the chain
  // of the datagram it joins (values are the same written against an empty chain).
  virtual bool send_slot(uint8_t /*config_id*/, uint64_t /*slot*/, int64_t /*date_ns*/,
                         std::vector<uint8_t>&& /*values*/, std::vector<bool>&& /*presence*/,
                         link::SlotEncoder&& /*enc*/ = {}) {
    return false;
  }
};

struct ExecutorCounters {
  uint64_t slots_fired = 0;
  uint64_t slots_empty = 0;  // every stream absent: nothing sent
  uint64_t frames_sent = 0;
  uint64_t frames_dropped = 0;
  uint64_t events_coalesced = 0;  // events beyond their window's N, counted in its last one
};

class Executor {
 public:
  static constexpr int64_t kNever = std::numeric_limits<int64_t>::max();

  // topic_globals[i]: the broker's topic index for CONFIG topic i.
  // Returns the epoch (ns) at which the config takes effect, or nullopt if a
  // config is already waiting for its switch date (answer BUSY).
  std::optional<int64_t> apply(const link::Config& cfg, const std::vector<uint32_t>& topic_globals,
                               int64_t now);
  void advance(int64_t t, FrameSink& sink);
  // t_ns: the sample's stamp (an event's time; windows hold the samples stamped inside them).
  void on_sample(uint32_t global_topic, double number, int64_t integer, int64_t t_ns = 0);
  int64_t next_due_ns() const;
  uint8_t config_id() const { return active_ ? active_->config_id : 0; }
  int64_t epoch_ns() const { return active_ ? active_->epoch : 0; }
  bool pending() const { return pending_ != nullptr; }
  void request_sync() { need_sync_ = true; }
  const ExecutorCounters& counters() const { return counters_; }

 private:
  struct Active {
    uint8_t config_id = 0;
    int64_t epoch = 0;
    std::vector<Accumulator> acc;
    std::vector<std::unique_ptr<EventDetector>> events;  // ON_CHANGE, THRESHOLD streams
    std::vector<uint64_t> periods_us;
    std::vector<link::ValueKind> kinds;
    std::vector<std::vector<uint32_t>> by_topic;  // global topic -> stream ids
    std::unique_ptr<link::SlotIterator> slots;
    int64_t next_due = kNever;
  };
  std::unique_ptr<Active> build(const link::Config& cfg, const std::vector<uint32_t>& topic_globals,
                                int64_t epoch);
  void fire(FrameSink& sink);
  link::Value take_events(Active& a, uint32_t id, int64_t date);
  void fire_slot(FrameSink& sink, const link::Data& d, const std::vector<link::ValueKind>& kinds,
                 const std::vector<uint32_t>& streams, int64_t date);

  std::unique_ptr<Active> active_, pending_;
  int64_t switch_at_ = kNever;
  bool need_sync_ = true;
  ExecutorCounters counters_;
};

}  // namespace modd::broker
