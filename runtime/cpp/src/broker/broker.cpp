#include "modd/broker/broker.hpp"

#include <sys/statvfs.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "modd/broker/health.hpp"
#include "modd/broker/onboard.hpp"
#include "modd/link/auth.hpp"
#include "modd/link/codec.hpp"
#include "modd/util/bytes.hpp"
#include "modd/util/log.hpp"

namespace modd::broker {

// ---- ingress ---------------------------------------------------------------

IngressSession::IngressSession(Broker& b) : broker_(b) { broker_.attach(this); }
IngressSession::~IngressSession() {
  broker_.detach(this);
  // Its instruments leave STATUS now (within the change budget), not at the next period.
  if (!health_.empty()) broker_.want_change_status();  // sent by the server's next tick
}

void IngressSession::on_hello(const ingress::Hello& h) {
  publisher_ = h.publisher;
  version_ = h.version;
  send_catalogue_if_changed();
}

void IngressSession::send_catalogue_if_changed() {
  if (version_ < 2 || catalogue_generation_ == broker_.topics_generation()) return;
  catalogue_generation_ = broker_.topics_generation();
  ingress::encode_catalogue(out_, broker_.catalogue());
}

void IngressSession::on_register(const ingress::Register& r) {
  if (locals_.size() <= r.local_id) locals_.resize(r.local_id + 1);
  Local& l = locals_[r.local_id];
  l.used = true;
  l.type = r.type;
  l.reject = kAccepted;
  l.topic = r.topic;
  l.global = broker_.find_topic(r.topic, r.type, l.reject);
  l.generation = broker_.topics_generation();
}

void IngressSession::on_health(std::vector<link::SensorHealth>&& sensors) {
  // New instruments, or a change of one's state (field 0: closed, open, silent), ask for a
  // STATUS now, within the change budget (Broker::instruments_changed): the operator hears of
  // an unplugged device at once, and a flapping one costs at most one STATUS a period.
  for (auto& h : sensors) broker_.counters().health_corrected += sanitise_health(h);
  auto states = [](const std::vector<link::SensorHealth>& v) {
    std::vector<std::pair<std::string, uint64_t>> out;
    for (const auto& h : v) out.emplace_back(h.name, h.fields.empty() ? 0 : h.fields[0]);
    return out;
  };
  bool changed = states(health_) != states(sensors);
  health_ = std::move(sensors);
  if (changed) broker_.instruments_changed();
}

bool IngressSession::type_of(uint32_t id, link::ValueType& out) const {
  if (id >= locals_.size() || !locals_[id].used) return false;
  out = locals_[id].type;
  return true;
}

void IngressSession::on_record(const ingress::Record& r) {
  Local& l = locals_[r.local_id];
  if (l.generation != broker_.topics_generation()) {
    // Topics were added or retyped (a CONFIG) since the registration: resolve again.
    l.reject = kAccepted;
    l.global = broker_.find_topic(l.topic, l.type, l.reject);
    l.generation = broker_.topics_generation();
  }
  Reject why = broker_.ingest(l.global, l.reject, l.type, stamp_, r, this);
  ++received_;
  if (why == kAccepted) {
    ++accepted_;
    return;
  }
  if (version_ < 2) return;
  Refused& f = refused_[{r.local_id, static_cast<uint8_t>(why)}];
  if (f.count++ == 0) f.detail = broker_.describe(why, l.topic, stamp_, r);
}

void IngressSession::checkpoint(uint64_t flush_id) {
  // Bounded while the archive stalls (disk full): the newest checkpoint replaces the last one,
  // which only delays the acknowledgement of the records in between.
  if (checkpoints_.size() >= 1024) checkpoints_.pop_back();
  checkpoints_.push_back({flush_id, received_, accepted_});
}

void IngressSession::report(uint64_t durable) {
  while (!checkpoints_.empty() && checkpoints_.front().flush_id <= durable) {
    settled_ = checkpoints_.front().received;
    archived_ = checkpoints_.front().accepted;
    checkpoints_.pop_front();
  }
  if (version_ < 2) return;
  if (out_.size() > 64 * 1024) out_.clear();  // a publisher that does not read: ACKs are cumulative
  for (auto& [key, f] : refused_) {
    if (!f.count) continue;
    ingress::encode_reject(out_, ingress::RejectMsg{key.first, key.second, f.count, f.detail});
    f.count = 0;
  }
  refused_.clear();
  if (acked_received_ != received_ || acked_settled_ != settled_) {
    ingress::encode_ack(out_, ingress::Ack{received_, settled_, archived_});
    acked_received_ = received_;
    acked_settled_ = settled_;
  }
}

bool IngressSession::on_bytes(std::span<const uint8_t> in) {
  stamp_ = broker_.stamp_now();
  inbuf_.insert(inbuf_.end(), in.begin(), in.end());
  size_t used = 0;
  uint64_t left = 0;
  try {
    while (auto f = ingress::split_frame(std::span(inbuf_).subspan(used), ingress::kMaxFrame)) {
      used += f->size;
      ingress::decode(*f, *this, &left);
    }
  } catch (const Error& e) {
    Counters& c = broker_.counters();
    ++c.ingress_malformed_frames;
    c.samples_in += left;
    c.rej(Reject::Malformed) += left;
    last_error = e.what();
    inbuf_.clear();
    return false;
  }
  inbuf_.erase(inbuf_.begin(), inbuf_.begin() + static_cast<std::ptrdiff_t>(used));
  return true;
}

bool IngressSession::on_close() {
  if (inbuf_.empty()) return false;
  Counters& c = broker_.counters();
  ++c.ingress_malformed_frames;
  // Length varint, type, then for SAMPLES the record count: count what was announced.
  size_t i = 0;
  while (i < inbuf_.size() && i < 4 && (inbuf_[i] & 0x80)) ++i;
  ++i;
  if (i + 1 < inbuf_.size() && inbuf_[i] == static_cast<uint8_t>(ingress::MsgType::Samples)) {
    try {
      ByteReader r(std::span<const uint8_t>(inbuf_).subspan(i + 1));
      uint64_t n = r.varint();
      n = std::min<uint64_t>(n, ingress::kMaxFrame / 10);
      c.samples_in += n;
      c.rej(Reject::Malformed) += n;
    } catch (const Error&) {}
  }
  inbuf_.clear();
  return true;
}

// ---- broker ----------------------------------------------------------------

Broker::Broker(const BrokerConfig& cfg, std::string key, Clock& clock, LinkOutput& out)
    : cfg_(cfg),
      key_(std::move(key)),
      time_(clock),
      out_(out),
      status_period_s_(cfg.status_period_s),
      backfill_(cfg.archive_dir, cfg.archive_prefix, cfg.backfill_default_rate_bps) {
  archive::ArchiverOptions ao;
  ao.dir = cfg.archive_dir;
  ao.prefix = cfg.archive_prefix;
  ao.rotate_bytes = cfg.rotate_bytes;
  ao.rotate_s = cfg.rotate_s;
  ao.writer.compression = cfg.compression;
  ao.writer.chunk_bytes = cfg.chunk_bytes;
  ao.writer.message_index = cfg.message_index;
  ao.writer.fsync = cfg.fsync;
  ao.retry_max_ms = cfg.retry_max_ms;
  archiver_ = std::make_unique<archive::Archiver>(ao);
  for (const auto& t : cfg.topics)
    add_topic(t.name, t.type, t.buffer_size ? t.buffer_size : cfg.default_buffer_size, true);
  started_ns_ = last_stamp_ = time_.now();
  clock_now_ = time_.wall();
  run_record_ = std::make_unique<RunRecord>(cfg.archive_dir, cfg.archive_prefix, started_ns_);
  write_run_record(started_ns_, false);
}

Broker::~Broker() { shutdown(); }

uint32_t Broker::add_topic(const std::string& name, link::ValueType type, uint32_t capacity,
                           bool known) {
  auto it = by_name_.find(name);
  if (it != by_name_.end()) {
    Topic& t = topics_[it->second];
    t.known = t.known || known;
    t.capacity = capacity;
    if (t.info->type != type) {
      // The type changes: the archive gets a new channel object (new schema).
      swap_out(t);
      t.info = std::make_shared<archive::TopicInfo>(archive::TopicInfo{name, type});
      ++generation_;
    }
    return it->second;
  }
  Topic t;
  t.info = std::make_shared<archive::TopicInfo>(archive::TopicInfo{name, type});
  t.known = known;
  t.capacity = capacity;
  topics_.push_back(std::move(t));
  by_name_[name] = static_cast<uint32_t>(topics_.size() - 1);
  ++generation_;
  return static_cast<uint32_t>(topics_.size() - 1);
}

int64_t Broker::find_topic(const std::string& name, link::ValueType declared, Reject& why) {
  auto it = by_name_.find(name);
  if (it == by_name_.end()) {
    if (!cfg_.accept_unknown_topics) {
      why = Reject::UnknownTopic;
      return -1;
    }
    return add_topic(name, declared, cfg_.default_buffer_size, false);
  }
  if (topics_[it->second].info->type != declared) {
    why = Reject::WrongType;
    return -1;
  }
  return it->second;
}

int64_t Broker::now() {
  int64_t t = time_.now();
  clock_now_ = time_.wall();
  if (Timeline::Step st = time_.last_step(); st.delta_ns != 0) {
    log_line(
        "clock: CLOCK_REALTIME stepped %+.3f s; stamps and the schedule keep the monotonic "
        "timeline "
        "(wall - timeline now %+.3f s, %llu step(s) this run)",
        static_cast<double>(st.delta_ns) / 1e9, static_cast<double>(time_.offset_ns()) / 1e9,
        static_cast<unsigned long long>(time_.steps()));
    run_record_->note_clock(time_.steps(), time_.offset_ns(), st);
  }
  return t;
}

int64_t Broker::stamp_now() {
  int64_t t = now();
  if (t < last_stamp_) t = last_stamp_;  // the timeline is monotonic: this only guards a fake clock
  last_stamp_ = t;
  executor_.advance(t, *this);
  return t;
}

Reject Broker::ingest(int64_t global, Reject why, link::ValueType declared, int64_t stamp,
                      const ingress::Record& r, const IngressSession* who) {
  ++counters_.samples_in;
  auto refuse = [&](Reject w) {
    ++counters_.rej(w);
    return w;
  };
  if (global < 0) return refuse(why);
  Topic& t = topics_[static_cast<size_t>(global)];
  if (t.info->type != declared) return refuse(Reject::WrongType);
  bool is_float = declared == link::ValueType::Float32 || declared == link::ValueType::Float64;
  if (is_float && !std::isfinite(r.number)) return refuse(Reject::NotFinite);
  // Judged against the broker's clock as it reads now, never against what came before: one
  // sample stamped in 2116 cannot block the samples after it, and after the clock jumps back
  // (the archive's stamps then hold until it catches up) samples stamped by the same clock
  // are still in bounds.
  __int128 ahead = static_cast<__int128>(r.timestamp_ns) - clock_now_;
  if (cfg_.max_future_ms && ahead > static_cast<__int128>(cfg_.max_future_ms) * 1'000'000)
    return refuse(Reject::Timestamp);
  if (cfg_.max_past_ms && -ahead > static_cast<__int128>(cfg_.max_past_ms) * 1'000'000)
    return refuse(Reject::Timestamp);
  uint64_t pending = archiver_->counters().queued + front_samples_;
  if (pending >= cfg_.queue_limit_samples) return refuse(Reject::Overflow);
  if (pending >= cfg_.queue_limit_samples / 2) {
    // Fair share: with the queue half full, a publisher (or topic) holding more than its share
    // of the samples not yet on disk loses its own samples, not the others'.
    uint64_t n = std::max<uint64_t>(counters_.publishers_connected, 1);
    uint64_t share = cfg_.publisher_quota_samples ? cfg_.publisher_quota_samples
                                                  : cfg_.queue_limit_samples / 2 / n;
    if (who && who->outstanding() >= share) return refuse(Reject::Quota);
    uint64_t tshare =
        cfg_.topic_quota_samples ? cfg_.topic_quota_samples : cfg_.queue_limit_samples / 4;
    if (t.accepted - t.durable_accepted >= tshare) return refuse(Reject::Quota);
  }
  ++counters_.accepted;
  ++t.accepted;
  executor_.on_sample(static_cast<uint32_t>(global), r.number, r.integer, stamp);
  if (t.front.capacity() == 0) {
    t.front = archiver_->take_spare();
    t.front.reserve(t.capacity);
  }
  t.front.push_back({stamp, r.timestamp_ns, r.number, r.integer});
  ++front_samples_;
  if (t.front.size() >= t.capacity) swap_out(t);
  return kAccepted;
}

std::string Broker::describe(Reject why, const std::string& topic, int64_t stamp,
                             const ingress::Record& r) const {
  char buf[320];
  switch (why) {
    case Reject::UnknownTopic:
      std::snprintf(buf, sizeof buf, "topic '%s' is not published on drone '%s'", topic.c_str(),
                    cfg_.name.c_str());
      break;
    case Reject::WrongType: {
      auto it = by_name_.find(topic);
      std::snprintf(
          buf, sizeof buf, "topic '%s' is %s on this drone", topic.c_str(),
          it == by_name_.end() ? "?" : link::value_type_name(topics_[it->second].info->type));
      break;
    }
    case Reject::NotFinite:
      std::snprintf(buf, sizeof buf, "topic '%s': value is NaN or infinite", topic.c_str());
      break;
    case Reject::Timestamp: {
      (void)stamp;
      double ahead_s =
          (static_cast<double>(r.timestamp_ns) - static_cast<double>(clock_now_)) / 1e9;
      std::snprintf(buf, sizeof buf,
                    "topic '%s': timestamp %lld ns is %.3g s %s the broker clock (bounds: %llu ms "
                    "ahead, %llu ms behind)",
                    topic.c_str(), static_cast<long long>(r.timestamp_ns), std::fabs(ahead_s),
                    ahead_s > 0 ? "ahead of" : "behind",
                    static_cast<unsigned long long>(cfg_.max_future_ms),
                    static_cast<unsigned long long>(cfg_.max_past_ms));
      break;
    }
    case Reject::Overflow:
      std::snprintf(buf, sizeof buf, "topic '%s': archive queue full (%llu samples)", topic.c_str(),
                    static_cast<unsigned long long>(cfg_.queue_limit_samples));
      break;
    case Reject::Quota:
      std::snprintf(
          buf, sizeof buf,
          "topic '%s': over this publisher's (or topic's) fair share of the archive queue",
          topic.c_str());
      break;
    default: std::snprintf(buf, sizeof buf, "topic '%s': %s", topic.c_str(), reject_name(why));
  }
  return buf;
}

ingress::Catalogue Broker::catalogue() const {
  ingress::Catalogue c;
  c.drone = cfg_.name;
  c.max_future_ms = cfg_.max_future_ms;
  c.max_past_ms = cfg_.max_past_ms;
  c.accept_unknown = cfg_.accept_unknown_topics;
  for (const Topic& t : topics_) c.topics.push_back({t.info->name, t.info->type});
  return c;
}

void Broker::swap_out(Topic& t) {
  if (t.front.empty()) return;
  front_samples_ -= t.front.size();
  archiver_->submit(t.info, std::move(t.front));
  t.front = archiver_->take_spare();
  t.front.reserve(t.capacity);
}

void Broker::tick(int64_t now) {
  if (now < last_stamp_) now = last_stamp_;
  last_stamp_ = now;
  executor_.advance(now, *this);
  if (onboard_wait_ && now >= onboard_wait_->next_ns) answer_onboard(now);
}

std::optional<link::OnboardAck> Broker::on_onboard(const link::Onboard& o) {
  auto refuse = [&](const std::string& why) {
    log_line("link: on-board model of config %u refused: %s", o.config_id, why.c_str());
    nlohmann::json doc = {{"pubbroker", {{"ok", false}, {"problem", why}}}};
    return onboard_ack(o.config_id, static_cast<uint8_t>(ErrorCode::BadConfig), doc.dump());
  };
  if (cfg_.onboard_model.empty())
    return refuse("this PubBroker keeps no on-board model file (--onboard-model)");
  try {
    std::string digest = write_onboard(cfg_.onboard_model, o.model);
    log_line("link: on-board model %s written to %s", digest.c_str(), cfg_.onboard_model.c_str());
    int64_t t = now();
    onboard_wait_ = OnboardWait{o.config_id, digest, t + int64_t{link::kOnboardWaitMs} * 1'000'000,
                                t + 50'000'000};
  } catch (const Error& e) { return refuse(e.what()); }
  return std::nullopt;
}

int64_t Broker::onboard_wake_ns() const {
  return onboard_wait_ ? onboard_wait_->next_ns : Executor::kNever;
}

void Broker::answer_onboard(int64_t now) {
  OnboardWait& w = *onboard_wait_;
  bool final = now >= w.deadline_ns;
  auto answers = onboard_answers(cfg_.onboard_model, w.digest, final);
  if (!answers) {
    w.next_ns = now + 50'000'000;  // looked at every 50 ms
    return;
  }
  std::vector<uint8_t> frame;
  link::encode(frame, onboard_ack(w.config_id, 0, *answers));
  size_t n = frame.size();
  if (out_.link_write(std::move(frame))) counters_.link_bytes_sent += n;
  onboard_wait_.reset();
}

void Broker::flush_buffers() {
  ++flush_id_;
  for (Topic& t : topics_) {
    swap_out(t);
    if (t.checkpoints.size() >= 1024) t.checkpoints.pop_back();
    t.checkpoints.emplace_back(flush_id_, t.accepted);
  }
  for (IngressSession* s : sessions_) s->checkpoint(flush_id_);
  archiver_->flush(flush_id_);
  // Every sample stamped before last_stamp_ is in this flush (stamps never go backwards).
  if (flush_stamps_.size() >= 1024) flush_stamps_.pop_front();
  flush_stamps_.emplace_back(flush_id_, last_stamp_);
}

void Broker::check_archive(int64_t now) {
  const auto& ac = archiver_->counters();
  uint64_t durable = ac.durable_flush;
  if (durable != durable_seen_) {
    durable_seen_ = durable;
    while (!flush_stamps_.empty() && flush_stamps_.front().first <= durable) {
      archived_until_ = flush_stamps_.front().second;
      flush_stamps_.pop_front();
    }
    for (Topic& t : topics_)
      while (!t.checkpoints.empty() && t.checkpoints.front().first <= durable) {
        t.durable_accepted = t.checkpoints.front().second;
        t.checkpoints.pop_front();
      }
    // The record first: an acknowledgement a publisher holds is always backed by a record
    // that counts it archived.
    write_run_record(now, false);
    for (IngressSession* s : sessions_) s->report(durable);
  } else if (ac.files != record_files_ ||
             (now >= next_record_ns_ && counters_.samples_in != record_samples_in_)) {
    write_run_record(now, false);
  }
  for (IngressSession* s : sessions_) s->send_catalogue_if_changed();
  bool changed = false;
  if (ac.state_changes != archive_state_changes_) {
    archive_state_changes_ = ac.state_changes;
    changed = true;
  }
  if (now >= next_space_check_) {
    next_space_check_ = now + 1'000'000'000;
    struct statvfs sv {};
    if (statvfs(cfg_.archive_dir.c_str(), &sv) == 0) {
      uint64_t free_mb = static_cast<uint64_t>(sv.f_bavail) * sv.f_frsize / (1024 * 1024);
      bool low = free_mb < cfg_.low_space_mb;
      if (low != low_space_) {
        low_space_ = low;
        changed = true;
        if (low)
          log_line(
              "archive: low space: %llu MiB free under %s (threshold %llu MiB, writing %llu B/s)",
              static_cast<unsigned long long>(free_mb), cfg_.archive_dir.c_str(),
              static_cast<unsigned long long>(cfg_.low_space_mb),
              static_cast<unsigned long long>(rate_bps_));
        else
          log_line("archive: space back above the threshold: %llu MiB free",
                   static_cast<unsigned long long>(free_mb));
      }
    }
    if (now - rate_since_ >= 10'000'000'000) {
      uint64_t b = ac.bytes;
      if (rate_since_)
        rate_bps_ = (b - std::min(b, rate_bytes_)) * 1'000'000'000 /
                    static_cast<uint64_t>(now - rate_since_);
      rate_bytes_ = b;
      rate_since_ = now;
    }
  }
  uint8_t state = ac.disk_full ? kArchiveDiskFull : low_space_ ? kArchiveLowSpace : kArchiveOk;
  if (state != archive_state_) {
    archive_state_ = state;
    changed = true;
  }
  if (changed) want_change_status();  // the operator hears of it now, not at the next period
}

void Broker::instruments_changed() {
  want_change_status();
  send_overdue_status(now());
}

void Broker::want_change_status() {
  // A change: one STATUS of its own at most every change gap (the change budget,
  // docs/protocol.md "STATUS"); changes in between are coalesced into the next one.
  if (change_wanted_) ++counters_.status_coalesced;
  change_wanted_ = true;
}

int64_t Broker::change_gap_ns() const {
  return int64_t{std::min(status_period_s_, kMaxChangeGapS)} * 1'000'000'000;
}

int64_t Broker::status_wake_ns() const {
  if (!change_wanted_ || status_period_s_ == 0) return Executor::kNever;
  return last_change_status_ns_ + change_gap_ns();
}

void Broker::shutdown() {
  if (!archiver_ || shut_down_) return;
  shut_down_ = true;
  flush_buffers();
  archiver_->stop();
  write_run_record(now(), true);
}

void Broker::write_run_record(int64_t now, bool final) {
  std::vector<uint64_t> v = status_counters();  // `archived` read before the files: never more
  std::vector<std::pair<std::string, uint64_t>> counters;
  counters.reserve(v.size());
  for (size_t i = 0; i < kStatusFieldCount; ++i) counters.emplace_back(kStatusFieldLabels[i], v[i]);
  run_record_->write(counters, archiver_->files(), final, now);
  record_files_ = v[at(StatusField::ArchiveFiles)];
  record_samples_in_ = counters_.samples_in;
  next_record_ns_ = now + 1'000'000'000;
}

link::ConfigAck Broker::on_config(const link::Config& cfg) {
  link::ConfigAck ack;
  ack.config_id = cfg.config_id;
  // Validate before touching anything: types of existing topics must agree.
  std::vector<uint32_t> globals;
  for (const auto& t : cfg.topics) {
    auto it = by_name_.find(t.name);
    if (it != by_name_.end() && topics_[it->second].info->type != t.type) {
      ack.status = static_cast<uint8_t>(ErrorCode::BadConfig);
      log_line("config %u rejected: topic %s is %s here, %s in CONFIG", cfg.config_id,
               t.name.c_str(), link::value_type_name(topics_[it->second].info->type),
               link::value_type_name(t.type));
      return ack;
    }
  }
  if (executor_.pending()) {
    ack.status = static_cast<uint8_t>(ErrorCode::Busy);
    return ack;
  }
  for (const auto& t : cfg.topics)
    globals.push_back(add_topic(t.name, t.type, t.buffer_size, true));
  int64_t now = stamp_now();
  auto epoch = executor_.apply(cfg, globals, now);
  if (!epoch) {
    ack.status = static_cast<uint8_t>(ErrorCode::Busy);
    return ack;
  }
  ack.epoch_ns = static_cast<uint64_t>(*epoch);
  status_period_s_ = cfg.status_period_s;
  log_line("config %u accepted: %zu topics, %zu streams, epoch %lld", cfg.config_id,
           cfg.topics.size(), cfg.streams.size(), static_cast<long long>(*epoch));
  return ack;
}

link::AuthOk Broker::current_config() {
  link::AuthOk ok;
  ok.config_id = executor_.config_id();
  ok.epoch_ns = static_cast<uint64_t>(executor_.epoch_ns());
  return ok;
}

void Broker::on_authenticated() {
  ++counters_.link_sessions;
  executor_.request_sync();
  backfill_.clear();  // the base station asks again, with its resume points
  log_line("link: base station authenticated");
}

void Broker::on_backfill(const link::RawFrame& f, std::vector<uint8_t>& out) {
  namespace bf = link::backfill;
  if (f.type == static_cast<uint8_t>(bf::Type::Data) ||
      f.type == static_cast<uint8_t>(bf::Type::Progress) ||
      f.type == static_cast<uint8_t>(bf::Type::End))
    throw Error(ErrorCode::BadFrame, "backfill answers are sent by the PubBroker only", 0);
  bf::Message m = bf::decode(f);
  if (auto* c = std::get_if<bf::Cancel>(&m)) return backfill_.on_cancel(c->request_id, out);
  const auto& r = std::get<bf::Request>(m);
  std::optional<link::ValueType> known;
  auto it = by_name_.find(r.topic);
  if (it != by_name_.end()) known = topics_[it->second].info->type;
  backfill_.on_request(r, known, out);
}

void Broker::pump_backfill(int64_t now) {
  if (!backfill_.active()) return;
  BackfillSender::Env env{now, archived_until_, executor_.next_due_ns(),
                          out_.link_ready() && out_.link_backlog() == 0};
  std::vector<std::vector<uint8_t>> frames;
  backfill_.pump(env, frames);
  for (auto& f : frames) {
    size_t n = f.size();
    if (out_.link_write(std::move(f))) counters_.link_bytes_sent += n;
  }
}

void Broker::on_rejected(const std::string& why) {
  ++counters_.auth_failures;
  log_line("link: peer rejected: %s", why.c_str());
}

bool Broker::send_data(std::vector<uint8_t>&& frame) {
  if (!out_.link_ready()) return false;
  if (status_pending_) {
    // STATUS rides in the same write as the DATA frame: no segment of its own.
    link::encode(frame, status_message());
    status_pending_ = false;
  }
  size_t n = frame.size();
  if (!out_.link_write(std::move(frame))) return false;
  counters_.link_bytes_sent += n;
  return true;
}

bool Broker::send_slot(uint8_t config_id, uint64_t slot, int64_t date_ns,
                       std::vector<uint8_t>&& values, std::vector<bool>&& presence,
                       link::SlotEncoder&& enc) {
  if (!out_.link_ready()) return false;
  if (status_pending_) {
    // STATUS goes in a CONTROL datagram of its own: DATA datagrams carry slots only.
    std::vector<uint8_t> frame;
    link::encode(frame, status_message());
    if (out_.link_write(std::move(frame))) status_pending_ = false;
  }
  size_t n = values.size();
  if (!out_.link_slot(config_id, slot, date_ns, std::move(values), std::move(presence),
                      std::move(enc)))
    return false;
  counters_.link_bytes_sent += n;
  return true;
}

void Broker::status_due(int64_t now) {
  if (!status_pending_) status_due_since_ = now;
  status_pending_ = true;
}

void Broker::send_overdue_status(int64_t now) {
  int64_t period = int64_t{status_period_s_} * 1'000'000'000;
  if (change_wanted_ && (period == 0 || now - last_change_status_ns_ >= change_gap_ns())) {
    change_wanted_ = false;  // no STATUS at all when the period is 0
    if (period) {
      last_change_status_ns_ = now;
      status_pending_ = true;
      status_due_since_ = INT64_MIN / 2;  // overdue: sent on its own at once if the link is up
    }
  }
  if (!status_pending_ || period == 0 || now - status_due_since_ < period || !out_.link_ready())
    return;
  std::vector<uint8_t> frame;
  link::encode(frame, status_message());
  size_t n = frame.size();
  if (out_.link_write(std::move(frame))) {
    counters_.link_bytes_sent += n;
    status_pending_ = false;
  }
}

std::vector<link::SensorHealth> Broker::instruments() const {
  std::vector<link::SensorHealth> all;
  for (const IngressSession* s : sessions_)
    all.insert(all.end(), s->health().begin(), s->health().end());
  return all;
}

link::Status Broker::status_message() {
  return fit_status(status_counters(), instruments(), status_room_);
}

std::vector<uint64_t> Broker::status_counters() {
  std::vector<uint64_t> v(kStatusFieldCount, 0);
  const auto& ac = archiver_->counters();
  const auto& ec = executor_.counters();
  v[at(StatusField::UptimeS)] = static_cast<uint64_t>((now() - started_ns_) / 1'000'000'000);
  v[at(StatusField::SamplesIn)] = counters_.samples_in;
  // One read of each writer counter, so that the STATUS reconciles exactly.
  const uint64_t archived = ac.archived, failed = ac.failed;
  v[at(StatusField::SamplesArchived)] = archived;
  v[at(StatusField::RejectedUnknownTopic)] = counters_.rej(Reject::UnknownTopic);
  v[at(StatusField::RejectedWrongType)] = counters_.rej(Reject::WrongType);
  v[at(StatusField::RejectedNotFinite)] = counters_.rej(Reject::NotFinite);
  v[at(StatusField::RejectedTimestamp)] = counters_.rej(Reject::Timestamp);
  v[at(StatusField::RejectedOverflow)] = counters_.rej(Reject::Overflow);
  v[at(StatusField::RejectedMalformed)] = counters_.rej(Reject::Malformed);
  v[at(StatusField::ArchiveFailed)] = failed;
  v[at(StatusField::IngressMalformedFrames)] = counters_.ingress_malformed_frames;
  v[at(StatusField::PublishersConnected)] = counters_.publishers_connected;
  v[at(StatusField::FramesSent)] = ec.frames_sent;
  v[at(StatusField::FramesDropped)] = ec.frames_dropped;
  v[at(StatusField::LinkBytesSent)] = counters_.link_bytes_sent;
  struct statvfs sv {};
  if (statvfs(cfg_.archive_dir.c_str(), &sv) == 0)
    v[at(StatusField::DiskFreeMb)] =
        static_cast<uint64_t>(sv.f_bavail) * sv.f_frsize / (1024 * 1024);
  uint64_t fill = 0;
  for (const Topic& t : topics_)
    if (t.capacity) fill = std::max<uint64_t>(fill, t.front.size() * 100 / t.capacity);
  v[at(StatusField::BufferFillPct)] = fill;
  v[at(StatusField::ArchiveFiles)] = ac.files;
  v[at(StatusField::AuthFailures)] = counters_.auth_failures;
  v[at(StatusField::ConfigId)] = executor_.config_id();
  v[at(StatusField::RejectedQuota)] = counters_.rej(Reject::Quota);
  v[at(StatusField::ArchiveState)] = archive_state_;
  v[at(StatusField::ArchiveRateBps)] = rate_bps_;
  uint64_t settled = archived + failed;
  v[at(StatusField::SamplesPending)] =
      counters_.accepted > settled ? counters_.accepted - settled : 0;
  const LinkDatagramCounts d = out_.datagram_counts();
  v[at(StatusField::LinkDatagramsSent)] = d.sent;
  v[at(StatusField::LinkDatagramsResent)] = d.resent;
  v[at(StatusField::LinkNacks)] = d.nacks;
  v[at(StatusField::LinkSlotsDropped)] = d.dropped;
  v[at(StatusField::LinkForged)] = d.forged;
  v[at(StatusField::LinkReplayed)] = d.replayed;
  count_instruments(v, instruments());
  v[at(StatusField::HealthCorrected)] = counters_.health_corrected;
  v[at(StatusField::StatusCoalesced)] = counters_.status_coalesced;
  return v;
}

std::string Broker::log_summary() {
  auto v = status_counters();
  std::string s;
  for (size_t i = 0; i < kStatusFieldCount; ++i) {
    if (i) s += ' ';
    s += kStatusFieldLabels[i];
    s += '=';
    s += std::to_string(v[i]);
  }
  return s;
}

}  // namespace modd::broker
