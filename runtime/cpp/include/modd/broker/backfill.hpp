// The PubBroker's side of backfill (docs/protocol.md, "Backfill"): requests
// from the base station, their windows recomputed from the broker's own MCAP
// archive with the live path's Accumulator, and BACKFILL_DATA frames paced by
// a token bucket between live slots. Without sockets: the broker tells it the
// time, the archive horizon and when the next live slot is due, and sends what
// pump() returns. Memory is bounded: at most kMaxJobs requests, each holding
// one decompressed chunk, one open window and one frame's worth of windows.
// An event stream's request (ON_CHANGE, THRESHOLD) holds one detector: its state
// at the first window asked is rebuilt by replaying the archive from the
// request's state_from_ns (the config's epoch), at most kReplayStep samples
// per pump() (set_replay_step), so a long replay never holds up the live slots.
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "modd/archive/reader.hpp"
#include "modd/broker/accumulator.hpp"
#include "modd/broker/events.hpp"
#include "modd/link/backfill.hpp"

namespace modd::broker {

class BackfillSender {
 public:
  static constexpr size_t kMaxJobs = 8;
  // Archive samples an event request replays per pump() (a few ms of work).
  static constexpr size_t kReplayStep = 16384;
  void set_replay_step(size_t n) { replay_step_ = n ? n : 1; }  // tests: a replay in steps
  // Bytes a TCP segment adds on the wire (IPv4 + TCP with timestamps): what the pace
  // counts per frame unless the link says otherwise (set_frame_overhead).
  static constexpr size_t kSegmentOverhead = 52;

  struct Env {
    int64_t now = 0;
    int64_t archived_until = 0;  // every sample stamped before this is in a written chunk
    int64_t next_live_due = 0;   // date of the next live slot (INT64_MAX: none)
    bool link_idle = false;      // the link is up and nothing waits in its send queue
  };

  BackfillSender(std::string dir, std::string prefix, uint64_t default_rate_bps);
  // A request (replacing a running one with the same id) or a cancel. `known_type` is the
  // topic's type when the broker knows the topic. Replies (an END for a refusal) go to out.
  void on_request(const link::backfill::Request& r, std::optional<link::ValueType> known_type,
                  std::vector<uint8_t>& out);
  void on_cancel(uint64_t request_id, std::vector<uint8_t>& out);
  void clear() {
    jobs_.clear();
  }  // a new link session: the base station asks again with resume points
  // Appends the frames the pace allows now (each to be sent as its own write) to `frames`.
  void pump(const Env& env, std::vector<std::vector<uint8_t>>& frames);
  // When pump() next has something to do (INT64_MAX: nothing runs).
  int64_t next_wake_ns(int64_t now) const;
  size_t active() const { return jobs_.size(); }
  uint64_t bytes_sent() const { return bytes_sent_; }
  // Datagram links: a BACKFILL_DATA frame must fit one CONTROL datagram of at most
  // `max_datagram` bytes (0: no cap, tcp). Exact for every aggregation but ALL, whose one
  // window may be larger than any cap (then it goes alone and the radio may drop it).
  void set_max_datagram(size_t max_datagram) { max_datagram_ = max_datagram; }
  // Bytes the link adds to each frame on the wire, counted by the pace with the frame
  // (kSegmentOverhead on tcp; a datagram link's: control_frame_overhead()).
  void set_frame_overhead(size_t bytes) { frame_overhead_ = bytes; }
  size_t frame_overhead() const { return frame_overhead_; }
  // The cap on a frame's window bytes for the link (SIZE_MAX when none).
  size_t window_bytes_cap() const;

 private:
  struct Job {
    link::backfill::Request req;
    link::ValueKind kind;
    Accumulator acc;
    std::unique_ptr<EventDetector> events;  // ON_CHANGE, THRESHOLD
    int64_t replayed_to = 0;                // the detector's state holds the samples before
    archive::TopicReader reader;
    uint64_t next = 0;  // first window not sent
    std::vector<link::Value> batch;
    size_t batch_bytes = 0;
    bool waiting = false;  // the next window is not complete in the archive yet
    uint64_t bytes_sent = 0;
    int64_t last_progress = 0;
    uint64_t progress_next = 0;
    Job(const link::backfill::Request& r, const std::string& dir, const std::string& prefix);
  };
  uint64_t rate() const;
  size_t frame_budget() const;  // the pace's, capped by window_bytes_cap()
  void fill(Job& j, const Env& env);
  bool replay(Job& j, const Env& env);  // false: the detector is not at window `next` yet
  link::Value take_window(Job& j, int64_t start, int64_t end);
  void end(Job& j, link::backfill::EndStatus st, const std::string& why,
           std::vector<std::vector<uint8_t>>& frames);

  std::string dir_, prefix_;
  uint64_t default_rate_;
  std::vector<std::unique_ptr<Job>> jobs_;
  size_t turn_ = 0;    // round robin between jobs
  double credit_ = 0;  // token bucket, bytes; a frame goes when credit >= 0
  int64_t refilled_at_ = 0;
  uint64_t bytes_sent_ = 0;
  size_t max_datagram_ = 0;
  size_t frame_overhead_ = kSegmentOverhead;
  size_t replay_step_ = kReplayStep;
};

}  // namespace modd::broker
