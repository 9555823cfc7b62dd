#include "modd/archive/archiver.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>

#include "modd/archive/archive_record.gen.hpp"
#include "modd/archive/recover.hpp"
#include "modd/util/error.hpp"
#include "modd/util/log.hpp"

namespace modd::archive {

void format_sample_json(std::string& out, link::ValueType type, const Sample& s) {
  char buf[64];
  // {"<kValue>":<sample>}: the archive record (contracts/vectors/archive_record.json)
  out.assign("{\"");
  out.append(archive_record::kValue);
  out.append("\":");
  char* end = buf;
  switch (type) {
    case link::ValueType::Float32:
      end = std::to_chars(buf, buf + sizeof buf, static_cast<float>(s.number)).ptr;
      break;
    case link::ValueType::Float64: end = std::to_chars(buf, buf + sizeof buf, s.number).ptr; break;
    case link::ValueType::Int: end = std::to_chars(buf, buf + sizeof buf, s.integer).ptr; break;
    case link::ValueType::Bool:
      end = std::copy_n(s.integer ? "true" : "false", s.integer ? 4 : 5, buf);
      break;
  }
  out.append(buf, end);
  out.push_back('}');
}

std::string sample_json_schema(link::ValueType type) {
  return std::string(archive_record::kChannelSchemas[static_cast<int>(type) & 3]);
}

Archiver::Archiver(ArchiverOptions options) : opt_(std::move(options)) {
  std::error_code ec;
  std::filesystem::create_directories(opt_.dir, ec);
  if (ec)
    throw Error(ErrorCode::Io, "cannot create archive directory " + opt_.dir + ": " + ec.message());
  // Files a crash left open (no summary, torn tail) get finalised before anything new is written.
  for (Recovered& r : recover_dir(opt_.dir, opt_.prefix, opt_.writer))
    if (r.failed) unrecovered_.push_back(std::move(r.path));
  thread_ = std::thread([this] { run(); });
}

Archiver::~Archiver() { stop(); }

void Archiver::submit(std::shared_ptr<const TopicInfo> topic, std::vector<Sample>&& samples) {
  if (samples.empty()) return;
  counters_.queued += samples.size();
  {
    std::lock_guard lk(mu_);
    queue_.push_back(Item{std::move(topic), std::move(samples), false, 0, 0});
  }
  cv_.notify_one();
}

void Archiver::flush(uint64_t id) {
  {
    std::lock_guard lk(mu_);
    queue_.push_back(Item{nullptr, {}, true, id, 0});
  }
  cv_.notify_one();
}

void Archiver::stop() {
  {
    std::lock_guard lk(mu_);
    if (stopping_ && !thread_.joinable()) return;
    stopping_ = true;
  }
  cv_.notify_one();
  if (thread_.joinable()) thread_.join();
}

std::vector<Sample> Archiver::take_spare() {
  std::lock_guard lk(mu_);
  if (spares_.empty()) return {};
  auto v = std::move(spares_.back());
  spares_.pop_back();
  return v;
}

std::string Archiver::current_file() const {
  std::lock_guard lk(mu_);
  return current_file_;
}
std::vector<std::pair<std::string, uint64_t>> Archiver::files() const {
  std::lock_guard lk(mu_);
  return files_;
}
std::string Archiver::last_error() const {
  std::lock_guard lk(mu_);
  return last_error_;
}

void Archiver::run() {
  for (;;) {
    Item* item = nullptr;
    {
      std::unique_lock lk(mu_);
      if (counters_.disk_full) {
        // Hold everything queued (ingest refuses, counted, once the queue limit is reached)
        // and retry with backoff; no new file is opened meanwhile.
        cv_.wait_for(lk, std::chrono::milliseconds(backoff_ms_), [&] { return stopping_; });
        bool stopping = stopping_;
        lk.unlock();
        if (retry()) continue;
        if (stopping) {
          give_up();
          return;
        }
        backoff_ms_ = std::min(backoff_ms_ * 2, opt_.retry_max_ms);
        continue;
      }
      if (!unrecovered_.empty()) {
        // A file left by a crash that could not be finished for want of space: tried again
        // every 2 s and as soon as a write goes through again, not only at the next start.
        if (std::chrono::steady_clock::now() >= next_recovery_) {
          lk.unlock();
          retry_recovery();
          continue;
        }
        cv_.wait_until(lk, next_recovery_, [&] { return stopping_ || !queue_.empty(); });
        if (!stopping_ && queue_.empty()) continue;
      } else {
        cv_.wait(lk, [&] { return stopping_ || !queue_.empty(); });
      }
      if (queue_.empty()) break;  // stopping and drained
      item = &queue_.front();     // stays in the queue until written (only this thread pops)
    }
    if (!write_item(*item)) continue;
    std::lock_guard lk(mu_);
    Item done = std::move(queue_.front());
    queue_.pop_front();
    if (!done.flush) {
      done.samples.clear();
      if (spares_.size() < 64) spares_.push_back(std::move(done.samples));
    }
  }
  try {
    close_file();
  } catch (const Error& e) {
    set_disk_full(true, e.what());
    for (;;) {
      bool stopping;
      {
        std::unique_lock lk(mu_);
        stopping = stopping_;
      }
      if (retry()) return;
      if (stopping) {
        give_up();
        return;
      }
    }
  }
}

namespace {
// Seconds on the monotonic clock: a file's age for rotation, which a wall-clock step must not move.
int64_t steady_s() {
  using namespace std::chrono;
  return duration_cast<seconds>(steady_clock::now().time_since_epoch()).count();
}
}  // namespace

void Archiver::open_file() {
  std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &tm);
  char name[64];
  std::snprintf(name, sizeof name, "-%s-%04llu.mcap", stamp,
                static_cast<unsigned long long>(file_counter_++));
  std::string path = opt_.dir + "/" + opt_.prefix + name;
  std::error_code ec;
  while (std::filesystem::exists(path, ec)) {  // a restart within the same second: never overwrite
    std::snprintf(name, sizeof name, "-%s-%04llu.mcap", stamp,
                  static_cast<unsigned long long>(file_counter_++));
    path = opt_.dir + "/" + opt_.prefix + name;
  }
  writer_ = std::make_unique<McapWriter>(path, opt_.writer);
  file_opened_s_ = steady_s();
  channels_.clear();
  sequences_.clear();
  keep_.clear();
  seen_flushed_ = 0;
  ++counters_.files;
  std::lock_guard lk(mu_);
  current_file_ = path;
  if (files_.size() >= 4096) files_.erase(files_.begin());
  files_.emplace_back(opt_.prefix + name, 0);
}

void Archiver::count_flushed() {
  uint64_t f = writer_->flushed_messages();
  if (f != seen_flushed_) {
    std::lock_guard lk(mu_);
    if (!files_.empty()) files_.back().second = f;  // before `archived`: the record never says less
  }
  counters_.archived += f - seen_flushed_;
  seen_flushed_ = f;
  counters_.bytes = closed_bytes_ + writer_->file_bytes() - writer_->pending_bytes();
}

void Archiver::close_file() {
  if (!writer_) return;
  writer_->close();  // throws on a write error; close() resumes on the next call
  count_flushed();
  closed_bytes_ += writer_->file_bytes();
  counters_.bytes = closed_bytes_;
  writer_.reset();
}

void Archiver::set_disk_full(bool full, const std::string& why) {
  if (counters_.disk_full == full) return;
  counters_.disk_full = full;
  ++counters_.state_changes;
  if (full) {
    backoff_ms_ = opt_.retry_first_ms;
    {
      std::lock_guard lk(mu_);
      last_error_ = why;
    }
    log_line(
        "archive: write failed (%s): holding %llu queued samples in memory, no new file, retrying "
        "every "
        "%u..%u ms",
        why.c_str(), static_cast<unsigned long long>(counters_.queued.load()), opt_.retry_first_ms,
        opt_.retry_max_ms);
  } else {
    log_line("archive: writing again (%s resumed where it stopped)", current_file().c_str());
    next_recovery_ = {};  // room again: a file left by a crash is finished now too
  }
}

bool Archiver::retry() {
  try {
    if (writer_) {
      if (writer_->closing()) {
        close_file();
      } else {
        writer_->flush_chunk();
        count_flushed();
      }
    }
    set_disk_full(false, "");
    return true;
  } catch (const Error&) { return false; }
}

void Archiver::retry_recovery() {
  std::vector<std::string> still;
  for (std::string& path : unrecovered_) {
    try {
      Recovered r = recover_mcap(path, opt_.writer);
      log_recovered(std::filesystem::path(path).filename().string(), r, " now that there is room");
    } catch (const Error&) { still.push_back(std::move(path)); }
  }
  unrecovered_ = std::move(still);
  next_recovery_ = std::chrono::steady_clock::now() + std::chrono::seconds(2);
}

void Archiver::give_up() {
  uint64_t lost = 0;
  if (writer_) {
    lost += writer_->message_count() - writer_->flushed_messages();
    log_line(
        "archive: stopping with the disk still full: %s left unfinished (recovered at next start)",
        writer_->path().c_str());
    writer_->abandon();
    writer_.reset();
  }
  std::lock_guard lk(mu_);
  for (Item& it : queue_) {
    if (it.flush) continue;
    lost += it.samples.size() - it.done;
    counters_.queued -= it.samples.size();
  }
  queue_.clear();
  counters_.failed += lost;
  log_line("archive: %llu samples lost to the full disk (counted in archive_failed)",
           static_cast<unsigned long long>(lost));
}

bool Archiver::write_item(Item& item) {
  bool handed_over = false;  // every sample of the item is in the writer (counted out of queued)
  try {
    if (item.flush) {
      if (writer_) {
        writer_->flush_chunk();
        if (opt_.writer.fsync == FsyncPolicy::Chunk) writer_->sync();
        count_flushed();
      }
      if (item.flush_id) counters_.durable_flush = item.flush_id;
      return true;
    }
    if (!writer_) open_file();
    const TopicInfo* key = item.topic.get();
    auto it = channels_.find(key);
    if (it == channels_.end()) {
      const char* type = link::value_type_name(item.topic->type);
      uint16_t schema = writer_->add_schema(std::string(archive_record::kSchemaPrefix) + type,
                                            std::string(archive_record::kSchemaEncoding),
                                            sample_json_schema(item.topic->type));
      uint16_t ch = writer_->add_channel(schema, item.topic->name,
                                         std::string(archive_record::kMessageEncoding),
                                         {{std::string(archive_record::kTypeMetadataKey), type}});
      it = channels_.emplace(key, ch).first;
      keep_.push_back(item.topic);
    }
    uint32_t& seq = sequences_[key];
    std::string json;
    while (item.done < item.samples.size()) {
      const Sample& s = item.samples[item.done];
      format_sample_json(json, item.topic->type, s);
      writer_->append_message(
          it->second, seq++, static_cast<uint64_t>(s.stamp_ns), static_cast<uint64_t>(s.publish_ns),
          std::span(reinterpret_cast<const uint8_t*>(json.data()), json.size()));
      ++item.done;
      if (writer_->chunk_full()) {
        writer_->flush_chunk();
        count_flushed();
      }
    }
    counters_.queued -= item.samples.size();
    handed_over = true;
    count_flushed();
    // Age on the monotonic clock: a wall-clock step neither rotates nor holds the file.
    int64_t age = steady_s() - file_opened_s_;
    if (writer_->file_bytes() >= opt_.rotate_bytes ||
        writer_->chunk_count() >= opt_.rotate_chunks ||
        (opt_.rotate_s > 0 && age >= static_cast<int64_t>(opt_.rotate_s)))
      close_file();
    return true;
  } catch (const Error& e) {
    // Disk full or the like: nothing is dropped. What the writer took stays pending in it,
    // the rest of the item stays queued; the writer thread retries with backoff.
    if (!item.flush && item.done == item.samples.size()) {
      // Every sample is in the writer (pending there): the item is done; the loop now
      // retries the writer before taking the next one.
      if (!handed_over) counters_.queued -= item.samples.size();
      set_disk_full(true, e.what());
      return true;
    }
    set_disk_full(true, e.what());
    return false;
  }
}

}  // namespace modd::archive
