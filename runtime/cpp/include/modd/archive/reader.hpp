// Reads one topic's samples back from the broker's own MCAP archive, in file
// order (which is stamp order for one topic): the closed files and the
// complete chunks of the file being written, for backfill. Streams: holds
// one decompressed chunk at a time; skips chunks that end before the time
// asked for without decompressing them. Not thread-safe; one per backfill.
#pragma once
#include <cstdint>
#include <fstream>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "modd/link/messages.hpp"

namespace modd::archive {

struct ArchivedSample {
  int64_t stamp_ns = 0;  // MCAP log_time: the broker's ingest stamp, the window key
  double number = 0;     // float topics
  int64_t integer = 0;   // int and bool topics
};

class TopicReader {
 public:
  TopicReader(std::string dir, std::string prefix, std::string topic, link::ValueType type);
  // The next sample stamped at or after `from` (earlier ones are skipped), without
  // consuming it; nullopt when the archive holds no more yet (ask again later).
  // Throws Error(Io) on a file that cannot be read or a message that does not parse.
  std::optional<ArchivedSample> peek(int64_t from);
  void pop() { have_ = false; }

 private:
  bool next_file();
  bool read_record(int64_t from);  // false: nothing complete to read now
  void scan_chunk_records(int64_t from);
  bool take_message(const uint8_t* p, uint64_t len, int64_t from);
  void channel(const uint8_t* p, uint64_t len);

  std::string dir_, prefix_, topic_;
  link::ValueType type_;
  std::vector<std::string> files_;
  size_t file_ = 0;
  bool file_open_ = false, file_done_ = false;
  std::ifstream in_;
  uint64_t offset_ = 0;
  std::set<uint16_t> channels_;  // this topic's channel ids in the current file
  std::vector<uint8_t> chunk_, packed_;
  size_t chunk_at_ = 0;
  bool have_ = false;
  ArchivedSample sample_;
};

}  // namespace modd::archive
