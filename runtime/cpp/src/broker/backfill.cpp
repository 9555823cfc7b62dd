#include "modd/broker/backfill.hpp"

#include <algorithm>
#include <limits>

#include "modd/util/error.hpp"
#include "modd/util/log.hpp"

namespace modd::broker {

namespace bf = link::backfill;

namespace {
constexpr int64_t kPollNs = 20'000'000;  // archive not complete yet, live guard: look again
constexpr int64_t kProgressNs = 1'000'000'000;
constexpr int64_t kGuardNs = 100'000'000;
bool is_float(const link::ValueKind& k) {
  return k.scalar == link::ScalarKind::F32 || k.scalar == link::ScalarKind::F64;
}
// One archived sample into an event stream's detector (an int topic's as a double).
void feed(EventDetector& d, const link::ValueKind& k, const archive::ArchivedSample& s) {
  d.add(s.stamp_ns, is_float(k) ? s.number : static_cast<double>(s.integer));
}
}  // namespace

BackfillSender::Job::Job(const bf::Request& r, const std::string& dir, const std::string& prefix)
    : req(r),
      kind(link::value_kind(r.type, r.aggregation)),
      acc(r.type, r.aggregation, r.percentile),
      events(link::is_event(r.aggregation)
                 ? std::make_unique<EventDetector>(event_spec(r.aggregation, r.event))
                 : nullptr),
      replayed_to(static_cast<int64_t>(r.state_from_ns)),
      reader(dir, prefix, r.topic, r.type),
      next(r.resume),
      progress_next(r.resume) {}

BackfillSender::BackfillSender(std::string dir, std::string prefix, uint64_t default_rate_bps)
    : dir_(std::move(dir)),
      prefix_(std::move(prefix)),
      default_rate_(std::max<uint64_t>(default_rate_bps, 1)) {}

uint64_t BackfillSender::rate() const {
  uint64_t r = std::numeric_limits<uint64_t>::max();
  for (const auto& j : jobs_) r = std::min(r, j->req.rate_bps ? j->req.rate_bps : default_rate_);
  return jobs_.empty() ? default_rate_ : r;
}

size_t BackfillSender::window_bytes_cap() const {
  // CONTROL datagram: type 1 + counter varint <= 10 + tag 8; BACKFILL_DATA frame: length
  // varint <= 3 + type 1 + request id, first <= 10 each + count <= 3; and the window added
  // last may overshoot the budget by its value (<= 18 B: AVERAGE of f64 + count) and one
  // presence byte.
  constexpr size_t kOverhead = 19 + 27 + 18 + 1;
  if (max_datagram_ == 0) return SIZE_MAX;
  return max_datagram_ > kOverhead + 1 ? max_datagram_ - kOverhead : 1;
}

size_t BackfillSender::frame_budget() const {
  return std::min(static_cast<size_t>(std::clamp<uint64_t>(rate() / 16, 64, 16384)),
                  window_bytes_cap());
}

void BackfillSender::on_request(const bf::Request& r, std::optional<link::ValueType> known_type,
                                std::vector<uint8_t>& out) {
  std::erase_if(jobs_, [&](const auto& j) { return j->req.request_id == r.request_id; });
  auto refuse = [&](bf::EndStatus st, const std::string& why) {
    log_line("backfill %llu of %s refused: %s", static_cast<unsigned long long>(r.request_id),
             r.topic.c_str(), why.c_str());
    bf::encode(out, bf::End{r.request_id, st, r.resume, why});
  };
  if (known_type && *known_type != r.type)
    return refuse(bf::EndStatus::BadRequest, "topic " + r.topic + " is " +
                                                 link::value_type_name(*known_type) +
                                                 " here, not " + link::value_type_name(r.type));
  // The last window must end before 2262 (int64 nanoseconds).
  unsigned __int128 end =
      static_cast<unsigned __int128>(r.windows) * r.period_us * 1000 + r.from_ns;
  if (end > static_cast<unsigned __int128>(std::numeric_limits<int64_t>::max()))
    return refuse(bf::EndStatus::BadRequest, "the range ends beyond the year 2262");
  if (r.resume >= r.windows) {
    bf::encode(out, bf::End{r.request_id, bf::EndStatus::Done, r.windows, ""});
    return;
  }
  if (jobs_.size() >= kMaxJobs)
    return refuse(bf::EndStatus::Busy, "too many backfills at once, ask again later");
  jobs_.push_back(std::make_unique<Job>(r, dir_, prefix_));
  // The acknowledgement: the base station sends a request again until it hears of it.
  bf::encode(out, bf::Progress{r.request_id, r.resume, r.windows, 0,
                               r.rate_bps ? r.rate_bps : default_rate_});
  log_line("backfill %llu: %s %s over %llu us, windows %llu..%llu, %llu B/s",
           static_cast<unsigned long long>(r.request_id), r.topic.c_str(),
           link::aggregation_name(r.aggregation), static_cast<unsigned long long>(r.period_us),
           static_cast<unsigned long long>(r.resume),
           static_cast<unsigned long long>(r.windows - 1),
           static_cast<unsigned long long>(r.rate_bps ? r.rate_bps : default_rate_));
}

void BackfillSender::on_cancel(uint64_t id, std::vector<uint8_t>& out) {
  uint64_t next = 0;
  for (const auto& j : jobs_)
    if (j->req.request_id == id) next = j->next;
  std::erase_if(jobs_, [&](const auto& j) { return j->req.request_id == id; });
  bf::encode(out, bf::End{id, bf::EndStatus::Cancelled, next, "cancelled by the base station"});
}

// The detector's state at the first window to send: the archive's samples from the
// request's state_from_ns on, fed in (their events discarded), kReplayStep at a time.
bool BackfillSender::replay(Job& j, const Env& env) {
  int64_t until = j.req.window_start_ns(j.next + j.batch.size());
  if (!j.events || j.replayed_to >= until) return true;
  if (until > env.archived_until) return false;
  for (size_t n = 0; n < replay_step_; ++n) {
    auto smp = j.reader.peek(j.replayed_to);
    if (!smp || smp->stamp_ns >= until) {
      j.replayed_to = until;
      j.events->take();
      return true;
    }
    feed(*j.events, j.kind, *smp);
    j.replayed_to = smp->stamp_ns;
    j.reader.pop();
  }
  return false;
}

link::Value BackfillSender::take_window(Job& j, int64_t s, int64_t e) {
  for (;;) {
    auto smp = j.reader.peek(s);
    if (!smp || smp->stamp_ns >= e) break;
    if (j.events)
      feed(*j.events, j.kind, *smp);
    else
      j.acc.add(smp->number, smp->integer);
    j.reader.pop();
  }
  if (!j.events) return j.acc.take();
  j.replayed_to = e;
  return event_value(j.events->take(), s, is_float(j.kind));
}

void BackfillSender::fill(Job& j, const Env& env) {
  size_t budget = frame_budget();
  j.waiting = false;
  if (!replay(j, env)) {
    j.waiting = true;  // more to replay (next pump) or not archived yet
    return;
  }
  std::vector<uint8_t> tmp;
  while (j.batch_bytes < budget && j.batch.size() < bf::kMaxBatch) {
    uint64_t k = j.next + j.batch.size();
    if (k >= j.req.windows) break;
    int64_t s = j.req.window_start_ns(k);
    int64_t e = s + static_cast<int64_t>(j.req.period_us) * 1000;
    if (e > env.archived_until) {
      j.waiting = true;  // samples of this window may still be on their way to the archive
      break;
    }
    link::Value v = take_window(j, s, e);
    tmp.clear();
    if (v.present) link::encode_value(tmp, j.kind, v);
    j.batch_bytes += tmp.size() + (j.batch.size() % 8 == 0 ? 1 : 0);
    j.batch.push_back(std::move(v));
  }
}

void BackfillSender::end(Job& j, bf::EndStatus st, const std::string& why,
                         std::vector<std::vector<uint8_t>>& frames) {
  std::vector<uint8_t> f;
  bf::encode(f, bf::Progress{j.req.request_id, j.next, j.req.windows, j.bytes_sent, rate()});
  bf::encode(f, bf::End{j.req.request_id, st, j.next, why});
  frames.push_back(std::move(f));
  log_line("backfill %llu of %s ended (%d) at window %llu, %llu bytes%s%s",
           static_cast<unsigned long long>(j.req.request_id), j.req.topic.c_str(),
           static_cast<int>(st), static_cast<unsigned long long>(j.next),
           static_cast<unsigned long long>(j.bytes_sent), why.empty() ? "" : ": ", why.c_str());
}

void BackfillSender::pump(const Env& env, std::vector<std::vector<uint8_t>>& frames) {
  if (jobs_.empty()) return;
  double r = static_cast<double>(rate());
  if (refilled_at_ == 0 || env.now < refilled_at_) refilled_at_ = env.now;
  credit_ = std::min(0.0, credit_ + r * static_cast<double>(env.now - refilled_at_) / 1e9);
  refilled_at_ = env.now;
  if (!env.link_idle) return;
  while (credit_ >= 0 && !jobs_.empty()) {
    bool sent = false;
    for (size_t i = 0; i < jobs_.size() && !sent; ++i) {
      size_t at = (turn_ + i) % jobs_.size();
      Job& j = *jobs_[at];
      try {
        fill(j, env);
      } catch (const Error& e) {
        end(j, bf::EndStatus::Io, e.what(), frames);
        jobs_.erase(jobs_.begin() + static_cast<std::ptrdiff_t>(at));
        sent = true;
        break;
      }
      bool last = j.next + j.batch.size() >= j.req.windows;
      if (j.batch.empty()) {
        if (!last) continue;
        end(j, bf::EndStatus::Done, "", frames);
        jobs_.erase(jobs_.begin() + static_cast<std::ptrdiff_t>(at));
        sent = true;
        break;
      }
      if (j.batch_bytes < frame_budget() && j.batch.size() < bf::kMaxBatch && !last && !j.waiting)
        continue;
      std::vector<uint8_t> f;
      bf::encode_data(f, bf::DataFrame{j.req.request_id, j.next, j.batch}, j.kind);
      double cost = static_cast<double>(f.size() + frame_overhead_);
      // Live first: the frame goes only if it is through before the next slot: its time at
      // the pace (an upper bound of its air time, the pace being at most the radio's rate),
      // capped at kGuardNs so that a slow pace still finds room between 4 Hz slots.
      int64_t guard = std::min(static_cast<int64_t>(cost * 1e9 / r), kGuardNs);
      if (env.next_live_due - env.now < guard) return;
      j.next += j.batch.size();
      j.batch.clear();
      j.batch_bytes = 0;
      j.bytes_sent += f.size();
      bytes_sent_ += f.size();
      credit_ -= cost;
      if (env.now - j.last_progress >= kProgressNs) {
        size_t before = f.size();
        bf::encode(f, bf::Progress{j.req.request_id, j.next, j.req.windows, j.bytes_sent, rate()});
        credit_ -= static_cast<double>(f.size() - before);  // the pace covers PROGRESS too
        j.last_progress = env.now;
      }
      frames.push_back(std::move(f));
      turn_ = at + 1;
      sent = true;
    }
    if (!sent) break;
  }
}

int64_t BackfillSender::next_wake_ns(int64_t now) const {
  if (jobs_.empty()) return std::numeric_limits<int64_t>::max();
  int64_t wait = kPollNs;
  if (credit_ < 0)
    wait = std::max<int64_t>(static_cast<int64_t>(-credit_ * 1e9 / static_cast<double>(rate())),
                             1'000'000);
  return now + std::min(wait, int64_t{1'000'000'000});
}

}  // namespace modd::broker
