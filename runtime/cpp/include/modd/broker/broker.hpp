// The PubBroker's logic without sockets: topics and their double buffers,
// ingest with validation and counting, the archiver, the executor, and the
// link hooks. The server (server.hpp) moves bytes between sockets and this.
#pragma once
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "modd/archive/archiver.hpp"
#include "modd/broker/backfill.hpp"
#include "modd/broker/config.hpp"
#include "modd/broker/counters.hpp"
#include "modd/broker/executor.hpp"
#include "modd/broker/link_session.hpp"
#include "modd/broker/run_record.hpp"
#include "modd/ingress/codec.hpp"
#include "modd/util/clock.hpp"

namespace modd::broker {

// Where DATA (and STATUS riding along) goes: the server's link connection.
class LinkOutput {
 public:
  virtual ~LinkOutput() = default;
  virtual bool link_ready() const = 0;
  // One write: the bytes must leave in one send (one TCP segment when small).
  virtual bool link_write(std::vector<uint8_t>&& bytes) = 0;
  // Bytes written but not yet sent (backfill waits until the live bytes are out).
  virtual size_t link_backlog() const { return 0; }
  // Datagram transports: every slot goes here (FrameSink::send_slot), frames (STATUS)
  // through link_write as CONTROL datagrams.
  virtual bool datagrams() const { return false; }
  virtual bool link_slot(uint8_t /*config_id*/, uint64_t /*slot*/, int64_t /*date_ns*/,
                         std::vector<uint8_t>&& /*values*/, std::vector<bool>&& /*presence*/,
                         link::SlotEncoder&& /*enc*/) {
    return false;
  }
  // Datagram transports: the link's counters for STATUS (fields 24..29), zeros over tcp.
  virtual LinkDatagramCounts datagram_counts() const { return {}; }
};

class Broker;

// Most bytes of a STATUS frame over tcp: one segment with a DATA frame beside it.
inline constexpr size_t kStatusRoomTcp = 1400;
// A change (an instrument, the archive's state) is told within this many seconds at most,
// however long the status period (docs/protocol.md, "Instruments' health").
inline constexpr uint32_t kMaxChangeGapS = 10;

// One publisher connection's registrations, the decoder's handler, and (ingress version 2)
// what the broker tells the publisher: the topic catalogue, acknowledgements per archive
// flush and rejections (docs/ingress.md).
class IngressSession final : public ingress::Handler {
 public:
  explicit IngressSession(Broker& b);
  ~IngressSession() override;
  IngressSession(const IngressSession&) = delete;
  IngressSession& operator=(const IngressSession&) = delete;
  void on_hello(const ingress::Hello& h) override;
  void on_register(const ingress::Register& r) override;
  bool type_of(uint32_t local_id, link::ValueType& out) const override;
  void on_record(const ingress::Record& r) override;
  // The publisher's instruments (HEALTH), forwarded in STATUS while it stays connected.
  void on_health(std::vector<link::SensorHealth>&& sensors) override;
  const std::vector<link::SensorHealth>& health() const { return health_; }
  // Feeds received bytes, stamped `stamp`. Returns false (after counting) on a malformed frame.
  bool on_bytes(std::span<const uint8_t> in);
  // The publisher went away. A frame it left half-sent is counted as malformed (with the
  // records it announced, when its header arrived). Returns true if one was left.
  bool on_close();
  const std::string& publisher() const { return publisher_; }
  std::string last_error;

  // Bytes for the publisher (empty for a version-1 publisher); the server sends them.
  std::vector<uint8_t> take_output() { return std::move(out_); }
  // An archive flush was queued (id): records received so far become settled when it is done.
  void checkpoint(uint64_t flush_id);
  // Flushes up to `durable` are on disk: ACK what became settled, REJECT what was refused.
  void report(uint64_t durable);
  void send_catalogue_if_changed();
  uint64_t outstanding() const { return accepted_ - archived_; }  // accepted, not yet known on disk
  uint64_t accepted() const { return accepted_; }
  uint64_t rejected() const { return received_ - accepted_; }

 private:
  struct Local {
    bool used = false;
    link::ValueType type{};
    int64_t global = -1;
    Reject reject{};
    std::string topic;
    uint64_t generation = 0;
  };
  struct Checkpoint {
    uint64_t flush_id, received, accepted;
  };
  struct Refused {
    uint64_t count = 0;
    std::string detail;
  };
  Broker& broker_;
  std::string publisher_;
  uint8_t version_ = 0;
  std::vector<Local> locals_;
  std::vector<uint8_t> inbuf_, out_;
  std::vector<link::SensorHealth> health_;
  int64_t stamp_ = 0;
  uint64_t received_ = 0, accepted_ = 0, settled_ = 0, archived_ = 0;
  uint64_t acked_received_ = UINT64_MAX, acked_settled_ = 0;
  std::deque<Checkpoint> checkpoints_;
  std::map<std::pair<uint32_t, uint8_t>, Refused> refused_;
  uint64_t catalogue_generation_ = 0;
};

class Broker final : public LinkHooks, public FrameSink {
 public:
  Broker(const BrokerConfig& cfg, std::string key, Clock& clock, LinkOutput& out);
  ~Broker() override;

  // Stamps a batch: advances the schedule to the stamp first (window rule).
  int64_t stamp_now();
  // The broker's timeline (util/clock.hpp): what stamps, slot dates and timers read. Logs a
  // wall-clock step when it sees one.
  int64_t now();
  const Timeline& timeline() const { return time_; }
  // One record, validated and counted: Reject::kCount when accepted, else the reason.
  // `who` (may be null) is charged for the fair share of the archive queue.
  Reject ingest(int64_t global, Reject why, link::ValueType declared, int64_t stamp,
                const ingress::Record& r, const IngressSession* who = nullptr);
  // Words for a refusal, sent to the publisher (REJECT detail).
  std::string describe(Reject why, const std::string& topic, int64_t stamp,
                       const ingress::Record& r) const;
  ingress::Catalogue catalogue() const;
  void attach(IngressSession* s) { sessions_.push_back(s); }
  void detach(IngressSession* s) { std::erase(sessions_, s); }
  // Timers: archive state (disk full, low space) and acknowledgements to publishers.
  void check_archive(int64_t now);
  int64_t find_topic(const std::string& name, link::ValueType declared, Reject& why);
  // Timers.
  void tick(int64_t now);  // fires due slots (no sample arrived)
  void flush_buffers();    // every flush interval: partial front buffers to the archive
  void shutdown();         // SIGTERM: everything to the archive, files closed
  int64_t next_due_ns() const { return executor_.next_due_ns(); }
  void status_due(int64_t now);
  // STATUS normally rides with the next DATA frame; when no DATA has gone out for a whole
  // status period after it fell due (idle publishers), it is sent on its own.
  void send_overdue_status(int64_t now);
  std::vector<uint64_t> status_counters();
  // The counters and the connected publishers' instruments' health (sorted by name), as
  // many as fit the STATUS room, the others counted (health.hpp, fit_status).
  link::Status status_message();
  std::vector<link::SensorHealth> instruments() const;
  // Instruments appeared, left or one changed state: a STATUS within the change budget.
  void instruments_changed();
  // A change the operator should hear of (instruments, archive state): one STATUS of its own
  // at most every change gap (send_overdue_status sends it), changes between coalesced.
  void want_change_status();
  // When a coalesced change's STATUS falls due (Executor::kNever: none waits).
  int64_t status_wake_ns() const;
  // Least time between two change STATUS: the status period, at most kMaxChangeGapS.
  int64_t change_gap_ns() const;
  // Most bytes a STATUS frame takes (a datagram link: what one CONTROL datagram carries).
  void set_status_room(size_t bytes) { status_room_ = bytes; }
  std::string log_summary();

  // LinkHooks
  link::ConfigAck on_config(const link::Config& cfg) override;
  link::AuthOk current_config() override;
  void on_authenticated() override;
  void on_rejected(const std::string& why) override;
  void on_backfill(const link::RawFrame& f, std::vector<uint8_t>& out) override;
  std::optional<link::OnboardAck> on_onboard(const link::Onboard& o) override;
  // When the on-board processes' answers are looked at next (Executor::kNever: none awaited).
  int64_t onboard_wake_ns() const;
  // Backfill frames the pace allows now, between live slots (docs/protocol.md, "Backfill").
  void pump_backfill(int64_t now);
  int64_t backfill_wake_ns(int64_t now) const { return backfill_.next_wake_ns(now); }
  const BackfillSender& backfill() const { return backfill_; }
  // A datagram link: backfill frames fit one control datagram of at most `max_datagram`
  // bytes, and the pace counts the link's bytes per frame (`frame_overhead`).
  void set_backfill_link(size_t max_datagram, size_t frame_overhead) {
    backfill_.set_max_datagram(max_datagram);
    backfill_.set_frame_overhead(frame_overhead);
  }
  // FrameSink
  bool send_data(std::vector<uint8_t>&& frame) override;
  bool wants_slots() const override { return out_.datagrams(); }
  bool send_slot(uint8_t config_id, uint64_t slot, int64_t date_ns, std::vector<uint8_t>&& values,
                 std::vector<bool>&& presence, link::SlotEncoder&& enc = {}) override;

  Counters& counters() { return counters_; }
  uint64_t topics_generation() const { return generation_; }
  const Executor& executor() const { return executor_; }
  archive::Archiver& archiver() { return *archiver_; }
  const BrokerConfig& config() const { return cfg_; }
  uint32_t status_period_s() const { return status_period_s_; }

 private:
  struct Topic {
    std::shared_ptr<const archive::TopicInfo> info;
    bool known = false;
    uint32_t capacity = 1;
    std::vector<archive::Sample> front;
    uint64_t accepted = 0, durable_accepted = 0;            // fair share per topic
    std::deque<std::pair<uint64_t, uint64_t>> checkpoints;  // (flush id, accepted)
  };
  uint32_t add_topic(const std::string& name, link::ValueType type, uint32_t capacity, bool known);
  void swap_out(Topic& t);
  void write_run_record(int64_t now, bool final);
  void answer_onboard(int64_t now);
  struct OnboardWait {
    uint8_t config_id = 0;
    std::string digest;
    int64_t deadline_ns = 0, next_ns = 0;
  };
  std::optional<OnboardWait> onboard_wait_;

  BrokerConfig cfg_;
  std::string key_;
  Timeline time_;
  LinkOutput& out_;
  std::unique_ptr<archive::Archiver> archiver_;
  Executor executor_;
  Counters counters_;
  std::vector<Topic> topics_;
  std::unordered_map<std::string, uint32_t> by_name_;
  int64_t last_stamp_ = 0;
  int64_t clock_now_ =
      0;  // the wall clock's last reading: publishers' timestamps are judged against it
  int64_t started_ns_ = 0;
  uint64_t front_samples_ = 0;
  uint64_t generation_ = 1;
  bool status_pending_ = false;
  bool change_wanted_ = false;  // a change asked for a STATUS of its own (want_change_status)
  int64_t last_change_status_ns_ = INT64_MIN / 2;
  size_t status_room_ = kStatusRoomTcp;
  int64_t status_due_since_ = 0;
  uint32_t status_period_s_ = 0;
  std::vector<IngressSession*> sessions_;
  uint64_t flush_id_ = 0, durable_seen_ = 0, archive_state_changes_ = 0;
  uint8_t archive_state_ = 0;  // ArchiveStateCode
  bool low_space_ = false;
  int64_t next_space_check_ = 0, rate_since_ = 0;
  uint64_t rate_bytes_ = 0, rate_bps_ = 0;
  BackfillSender backfill_;
  std::deque<std::pair<uint64_t, int64_t>>
      flush_stamps_;                       // (flush id, stamp horizon at that flush)
  int64_t archived_until_ = 0;             // samples stamped before this are in written chunks
  std::unique_ptr<RunRecord> run_record_;  // this run's counters beside its archive files
  int64_t next_record_ns_ = 0;
  uint64_t record_files_ = 0, record_samples_in_ = 0;
  bool shut_down_ = false;
};

}  // namespace modd::broker
