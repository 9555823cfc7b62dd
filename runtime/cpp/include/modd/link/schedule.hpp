// The slot table, computed lazily from the streams' periods with a next-due
// heap (never materialising the hyperperiod). Slot k is the k-th distinct
// due date > 0 after the epoch; its streams are those whose period divides
// the date, in stream-id order.
#pragma once
#include <cstdint>
#include <queue>
#include <span>
#include <vector>

namespace modd::link {

struct Slot {
  uint64_t index = 0;             // k
  uint64_t offset_us = 0;         // due date after the epoch
  std::vector<uint32_t> streams;  // stream ids due, ascending
};

class SlotIterator {
 public:
  explicit SlotIterator(std::span<const uint64_t> stream_periods_us);
  bool empty() const { return periods_.empty(); }
  // Date of the next slot (after the epoch), without consuming it.
  uint64_t peek_offset_us() const;
  Slot next();

 private:
  struct Entry {
    uint64_t due;
    uint32_t group;  // index into periods_
    bool operator>(const Entry& o) const { return due != o.due ? due > o.due : group > o.group; }
  };
  std::vector<uint64_t> periods_;              // distinct periods
  std::vector<std::vector<uint32_t>> groups_;  // stream ids per distinct period
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap_;
  uint64_t next_index_ = 0;
};

}  // namespace modd::link
