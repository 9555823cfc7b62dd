// The counters of one PubBroker run, kept in the archive directory beside the files they
// count, so that a run ended by kill -9 (no final log line) still leaves its figures: the
// archive itself is the oracle of every run (docs/reliability.md, "Counters that reconcile").
//
// <archive dir>/<prefix>-run-<UTC start>-<pid>.counters.json, replaced atomically (written
// beside, then renamed) at every acknowledgement watermark (before the ACK goes out), at
// every new file, at least once a second while samples arrive, and with "final": true at a
// clean stop. Its contract: "counters" reconcile exactly (samples_in = samples_archived +
// archive_failed + every rejected_* + samples_pending); "files" names the archive files of
// this run with the messages of each in written chunks (never more than the file holds, even
// after kill -9 and recovery). Not fsynced: it survives a crash of the process, and a power
// cut leaves the last copy the file system kept.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace modd::broker {

class RunRecord {
 public:
  RunRecord(std::string dir, const std::string& prefix, int64_t started_ns);
  // False when it cannot be written (disk full): the previous copy stays; one log line per
  // change between written and not written.
  bool write(const std::vector<std::pair<std::string, uint64_t>>& counters,
             const std::vector<std::pair<std::string, uint64_t>>& files, bool final, int64_t now_ns);
  const std::string& path() const { return path_; }

 private:
  std::string dir_, path_, run_;
  int64_t started_ns_;
  bool failing_ = false;
};

}  // namespace modd::broker
