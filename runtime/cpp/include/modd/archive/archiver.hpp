// The archive writer thread: takes full (back) buffers from ingest through a
// bounded queue and writes them to rotating MCAP files, one channel per topic,
// JSON messages with a JSON schema. Ingest never waits on the disk: submit()
// only moves a vector under a mutex.
#pragma once
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <utility>
#include <vector>

#include "modd/archive/mcap_writer.hpp"
#include "modd/link/messages.hpp"

namespace modd::archive {

struct Sample {
  int64_t
      stamp_ns;  // broker timeline on ingest (util/clock.hpp): the MCAP log_time and the window key
  int64_t publish_ns;  // the publisher's own timestamp: the MCAP publish_time
  double number;       // float topics
  int64_t integer;     // int and bool topics
};

struct TopicInfo {
  std::string name;
  link::ValueType type;
};

struct ArchiverOptions {
  std::string dir;
  std::string prefix = "modd";
  uint64_t rotate_bytes = 256ull << 20;
  uint64_t rotate_s = 3600;
  // A file is also closed when it holds this many chunks: the open file's summary (one
  // chunk index per chunk, ~350 B each, written at close as MCAP asks) is held in memory
  // until then; this bounds it whatever the flush interval, rotate_s and rotate_bytes.
  uint64_t rotate_chunks = 4096;
  WriterOptions writer;
  uint32_t retry_first_ms = 250;  // after a write error: retry after this, doubling,
  uint32_t retry_max_ms = 2000;   // up to this
};

struct ArchiveCounters {
  std::atomic<uint64_t> archived{0};  // samples in a written chunk
  std::atomic<uint64_t> failed{0};    // samples lost to a write error (counted, logged)
  std::atomic<uint64_t> files{0};
  std::atomic<uint64_t> bytes{0};   // bytes of closed files + current file
  std::atomic<uint64_t> queued{0};  // samples waiting for the writer
  std::atomic<uint64_t> durable_flush{
      0};                              // id of the last flush() whose samples are all in the file
  std::atomic<bool> disk_full{false};  // a write failed; the writer holds the queue and retries
  std::atomic<uint64_t> state_changes{
      0};  // +1 at each disk_full change (the broker sends STATUS at once)
};

class Archiver {
 public:
  explicit Archiver(ArchiverOptions options);
  ~Archiver();  // stop()
  Archiver(const Archiver&) = delete;
  Archiver& operator=(const Archiver&) = delete;

  void submit(std::shared_ptr<const TopicInfo> topic, std::vector<Sample>&& samples);
  // The writer closes its open chunk (fsync with FsyncPolicy::Chunk) once the queue before
  // it is written, then sets counters().durable_flush to `id` (ids must increase).
  void flush(uint64_t id = 0);
  // Writes everything queued, closes the file, joins. With the disk still full it tries once
  // more, then counts what it holds as failed and leaves the file for recovery at next start.
  void stop();
  // Recycled vectors for the next front buffers (may return an empty one).
  std::vector<Sample> take_spare();
  const ArchiveCounters& counters() const { return counters_; }
  std::string current_file() const;
  std::string last_error() const;
  // The files this run opened (names, newest last; at most the last 4096) with the messages
  // of each in chunks written to it: never more than the file holds, even after a crash.
  std::vector<std::pair<std::string, uint64_t>> files() const;

 private:
  struct Item {
    std::shared_ptr<const TopicInfo> topic;
    std::vector<Sample> samples;
    bool flush = false;
    uint64_t flush_id = 0;
    size_t done = 0;  // samples already handed to the writer (an item resumes after a write error)
  };
  void run();
  bool write_item(Item& item);  // false: a write failed (disk full), the item stays at the front
  void open_file();
  void close_file();
  void count_flushed();
  void set_disk_full(bool full, const std::string& why);
  bool retry();           // resumes the interrupted write; true when it went through
  void give_up();         // at stop with the disk still full
  void retry_recovery();  // files a crash left that could not be finished at start

  ArchiverOptions opt_;
  ArchiveCounters counters_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::deque<Item> queue_;
  std::vector<std::vector<Sample>> spares_;
  bool stopping_ = false;
  std::thread thread_;
  // writer-thread state
  std::unique_ptr<McapWriter> writer_;
  int64_t file_opened_s_ = 0;
  uint64_t closed_bytes_ = 0;
  std::unordered_map<const TopicInfo*, uint16_t> channels_;
  std::unordered_map<const TopicInfo*, uint32_t> sequences_;
  std::vector<std::shared_ptr<const TopicInfo>> keep_;  // keeps channel keys alive
  std::string current_file_, last_error_;
  std::vector<std::pair<std::string, uint64_t>> files_;  // under mu_
  uint64_t file_counter_ = 0;
  uint64_t seen_flushed_ = 0;  // writer_->flushed_messages() already counted in archived
  uint32_t backoff_ms_ = 0;
  std::vector<std::string> unrecovered_;  // writer thread (after the constructor)
  std::chrono::steady_clock::time_point next_recovery_{};
};

// The JSON message for one sample: {"value":V,"publish_time_ns":T}.
void format_sample_json(std::string& out, link::ValueType type, const Sample& s);
std::string sample_json_schema(link::ValueType type);

}  // namespace modd::archive
