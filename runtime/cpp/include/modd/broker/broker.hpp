// The PubBroker's logic without sockets: topics and their double buffers,
// ingest with validation and counting, the archiver, the executor, and the
// link hooks. The server (server.hpp) moves bytes between sockets and this.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "modd/archive/archiver.hpp"
#include "modd/broker/config.hpp"
#include "modd/broker/counters.hpp"
#include "modd/broker/executor.hpp"
#include "modd/broker/link_session.hpp"
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
};

class Broker;

// One publisher connection's registrations, and the decoder's handler.
class IngressSession final : public ingress::Handler {
 public:
  explicit IngressSession(Broker& b) : broker_(b) {}
  void on_hello(const ingress::Hello& h) override { publisher_ = h.publisher; }
  void on_register(const ingress::Register& r) override;
  bool type_of(uint32_t local_id, link::ValueType& out) const override;
  void on_record(const ingress::Record& r) override;
  // Feeds received bytes, stamped `stamp`. Returns false (after counting) on a malformed frame.
  bool on_bytes(std::span<const uint8_t> in);
  // The publisher went away. A frame it left half-sent is counted as malformed (with the
  // records it announced, when its header arrived). Returns true if one was left.
  bool on_close();
  const std::string& publisher() const { return publisher_; }
  std::string last_error;

 private:
  struct Local {
    bool used = false;
    link::ValueType type{};
    int64_t global = -1;
    Reject reject{};
    std::string topic;
    uint64_t generation = 0;
  };
  Broker& broker_;
  std::string publisher_;
  std::vector<Local> locals_;
  std::vector<uint8_t> inbuf_;
  int64_t stamp_ = 0;
};

class Broker final : public LinkHooks, public FrameSink {
 public:
  Broker(const BrokerConfig& cfg, std::string key, Clock& clock, LinkOutput& out);
  ~Broker() override;

  // Stamps a batch: advances the schedule to the stamp first (window rule).
  int64_t stamp_now();
  // One validated record. Rejections are counted by reason.
  void ingest(int64_t global, Reject why, link::ValueType declared, int64_t stamp, const ingress::Record& r);
  int64_t find_topic(const std::string& name, link::ValueType declared, Reject& why);
  // Timers.
  void tick(int64_t now);      // fires due slots (no sample arrived)
  void flush_buffers();        // every flush interval: partial front buffers to the archive
  void shutdown();             // SIGTERM: everything to the archive, files closed
  int64_t next_due_ns() const { return executor_.next_due_ns(); }
  void status_due(int64_t now);
  // STATUS normally rides with the next DATA frame; when no DATA has gone out for a whole
  // status period after it fell due (idle publishers), it is sent on its own.
  void send_overdue_status(int64_t now);
  std::vector<uint64_t> status_counters();
  std::string log_summary();

  // LinkHooks
  link::ConfigAck on_config(const link::Config& cfg) override;
  link::AuthOk current_config() override;
  void on_authenticated() override;
  void on_rejected(const std::string& why) override;
  // FrameSink
  bool send_data(std::vector<uint8_t>&& frame) override;

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
    int64_t last_publish_ns = INT64_MIN;
  };
  uint32_t add_topic(const std::string& name, link::ValueType type, uint32_t capacity, bool known);
  void swap_out(Topic& t);

  BrokerConfig cfg_;
  std::string key_;
  Clock& clock_;
  LinkOutput& out_;
  std::unique_ptr<archive::Archiver> archiver_;
  Executor executor_;
  Counters counters_;
  std::vector<Topic> topics_;
  std::unordered_map<std::string, uint32_t> by_name_;
  int64_t last_stamp_ = 0;
  bool clock_warned_ = false;
  int64_t started_ns_ = 0;
  uint64_t front_samples_ = 0;
  uint64_t generation_ = 1;
  bool status_pending_ = false;
  int64_t status_due_since_ = 0;
  uint32_t status_period_s_ = 0;
  std::vector<uint8_t> status_frame_;
};

}  // namespace modd::broker
