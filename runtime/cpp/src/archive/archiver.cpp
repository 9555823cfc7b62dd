#include "modd/archive/archiver.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <ctime>
#include <filesystem>

#include "modd/util/error.hpp"
#include "modd/util/log.hpp"

namespace modd::archive {

void format_sample_json(std::string& out, link::ValueType type, const Sample& s) {
  char buf[64];
  out.assign("{\"value\":");
  char* end = buf;
  switch (type) {
    case link::ValueType::Float32: end = std::to_chars(buf, buf + sizeof buf, static_cast<float>(s.number)).ptr; break;
    case link::ValueType::Float64: end = std::to_chars(buf, buf + sizeof buf, s.number).ptr; break;
    case link::ValueType::Int: end = std::to_chars(buf, buf + sizeof buf, s.integer).ptr; break;
    case link::ValueType::Bool: end = std::copy_n(s.integer ? "true" : "false", s.integer ? 4 : 5, buf); break;
  }
  out.append(buf, end);
  out.push_back('}');
}

std::string sample_json_schema(link::ValueType type) {
  const char* t = type == link::ValueType::Int ? "integer" : type == link::ValueType::Bool ? "boolean" : "number";
  return std::string(R"({"type":"object","properties":{"value":{"type":")") + t + R"("}},"required":["value"]})";
}

Archiver::Archiver(ArchiverOptions options) : opt_(std::move(options)) {
  std::error_code ec;
  std::filesystem::create_directories(opt_.dir, ec);
  if (ec) throw Error(ErrorCode::Io, "cannot create archive directory " + opt_.dir + ": " + ec.message());
  thread_ = std::thread([this] { run(); });
}

Archiver::~Archiver() { stop(); }

void Archiver::submit(std::shared_ptr<const TopicInfo> topic, std::vector<Sample>&& samples) {
  if (samples.empty()) return;
  counters_.queued += samples.size();
  {
    std::lock_guard lk(mu_);
    queue_.push_back(Item{std::move(topic), std::move(samples), false});
  }
  cv_.notify_one();
}

void Archiver::flush() {
  {
    std::lock_guard lk(mu_);
    queue_.push_back(Item{nullptr, {}, true});
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
std::string Archiver::last_error() const {
  std::lock_guard lk(mu_);
  return last_error_;
}

void Archiver::run() {
  for (;;) {
    Item item;
    {
      std::unique_lock lk(mu_);
      cv_.wait(lk, [&] { return stopping_ || !queue_.empty(); });
      if (queue_.empty()) break;  // stopping and drained
      item = std::move(queue_.front());
      queue_.pop_front();
    }
    write_item(item);
    if (!item.flush) {
      item.samples.clear();
      std::lock_guard lk(mu_);
      if (spares_.size() < 64) spares_.push_back(std::move(item.samples));
    }
  }
  try {
    close_file();
  } catch (const Error& e) {
    log_line("archive: close failed: %s", e.what());
  }
}

void Archiver::open_file() {
  std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &tm);
  char name[64];
  std::snprintf(name, sizeof name, "-%s-%04llu.mcap", stamp, static_cast<unsigned long long>(file_counter_++));
  std::string path = opt_.dir + "/" + opt_.prefix + name;
  writer_ = std::make_unique<McapWriter>(path, opt_.writer);
  file_opened_s_ = now;
  channels_.clear();
  sequences_.clear();
  keep_.clear();
  ++counters_.files;
  std::lock_guard lk(mu_);
  current_file_ = path;
}

void Archiver::close_file() {
  if (!writer_) return;
  uint64_t before = writer_->flushed_messages();
  uint64_t total = writer_->message_count();
  writer_->close();
  counters_.archived += total - before;
  closed_bytes_ += writer_->file_bytes();
  counters_.bytes = closed_bytes_;
  writer_.reset();
}

void Archiver::write_item(Item& item) {
  try {
    if (item.flush) {
      if (writer_) {
        uint64_t before = writer_->flushed_messages();
        writer_->flush_chunk();
        if (opt_.writer.fsync == FsyncPolicy::Chunk) writer_->sync();
        counters_.archived += writer_->flushed_messages() - before;
      }
      return;
    }
    if (!writer_) open_file();
    const TopicInfo* key = item.topic.get();
    auto it = channels_.find(key);
    if (it == channels_.end()) {
      uint16_t schema = writer_->add_schema(std::string("modd.") + link::value_type_name(item.topic->type), "jsonschema",
                                            sample_json_schema(item.topic->type));
      uint16_t ch = writer_->add_channel(schema, item.topic->name, "json",
                                         {{"type", link::value_type_name(item.topic->type)}});
      it = channels_.emplace(key, ch).first;
      keep_.push_back(item.topic);
    }
    uint32_t& seq = sequences_[key];
    std::string json;
    uint64_t before = writer_->flushed_messages();
    for (const Sample& s : item.samples) {
      format_sample_json(json, item.topic->type, s);
      writer_->add_message(it->second, seq++, static_cast<uint64_t>(s.stamp_ns), static_cast<uint64_t>(s.publish_ns),
                           std::span(reinterpret_cast<const uint8_t*>(json.data()), json.size()));
    }
    counters_.archived += writer_->flushed_messages() - before;
    counters_.queued -= item.samples.size();
    counters_.bytes = closed_bytes_ + writer_->file_bytes();
    int64_t age = std::time(nullptr) - file_opened_s_;
    if (writer_->file_bytes() >= opt_.rotate_bytes || (opt_.rotate_s > 0 && age >= static_cast<int64_t>(opt_.rotate_s)))
      close_file();
  } catch (const Error& e) {
    // Disk full or the like: count what is lost, say so, and start a fresh file next time.
    if (!item.flush) {
      counters_.queued -= item.samples.size();
      counters_.failed += item.samples.size();
    }
    if (writer_) {
      uint64_t unflushed = writer_->message_count() - writer_->flushed_messages();
      counters_.failed += unflushed;
    }
    {
      std::lock_guard lk(mu_);
      last_error_ = e.what();
    }
    log_line("archive: %s", e.what());
    writer_.reset();
  }
}

}  // namespace modd::archive
