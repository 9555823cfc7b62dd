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
// cut leaves the last copy the file system kept. "clock" (after a wall-clock step only):
// {"steps", "wall_minus_timeline_ns", "last_step_at_ns", "last_step_ns"}.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "modd/util/clock.hpp"

namespace modd::broker {

class RunRecord {
 public:
  RunRecord(std::string dir, const std::string& prefix, int64_t started_ns);
  // False when it cannot be written (disk full): the previous copy stays; one log line per
  // change between written and not written.
  bool write(const std::vector<std::pair<std::string, uint64_t>>& counters,
             const std::vector<std::pair<std::string, uint64_t>>& files, bool final,
             int64_t now_ns);
  const std::string& path() const { return path_; }
  // Wall-clock steps seen this run (util/clock.hpp, Timeline): written as "clock" with the
  // next record, so that a reader can map the archive's log times to the wall clock.
  void note_clock(uint64_t steps, int64_t wall_minus_timeline_ns, Timeline::Step last);

 private:
  std::string dir_, path_, run_;
  int64_t started_ns_;
  bool failing_ = false;
  uint64_t clock_steps_ = 0;
  int64_t clock_offset_ns_ = 0;
  Timeline::Step clock_last_{0, 0};
};

}  // namespace modd::broker
