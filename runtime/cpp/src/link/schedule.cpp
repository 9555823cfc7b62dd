#include "modd/link/schedule.hpp"

#include <algorithm>

#include "modd/util/error.hpp"

namespace modd::link {

SlotIterator::SlotIterator(std::span<const uint64_t> periods) {
  for (uint32_t id = 0; id < periods.size(); ++id) {
    if (periods[id] == 0)
      throw Error(ErrorCode::BadConfig, "stream " + std::to_string(id) + " has period 0");
    auto it = std::find(periods_.begin(), periods_.end(), periods[id]);
    if (it == periods_.end()) {
      periods_.push_back(periods[id]);
      groups_.push_back({id});
    } else {
      groups_[static_cast<size_t>(it - periods_.begin())].push_back(id);
    }
  }
  for (uint32_t g = 0; g < periods_.size(); ++g) heap_.push({periods_[g], g});
}

uint64_t SlotIterator::peek_offset_us() const { return heap_.empty() ? 0 : heap_.top().due; }

Slot SlotIterator::next() {
  Slot s;
  if (heap_.empty()) return s;
  s.index = next_index_++;
  s.offset_us = heap_.top().due;
  while (!heap_.empty() && heap_.top().due == s.offset_us) {
    Entry e = heap_.top();
    heap_.pop();
    const auto& ids = groups_[e.group];
    s.streams.insert(s.streams.end(), ids.begin(), ids.end());
    heap_.push({e.due + periods_[e.group], e.group});
  }
  std::sort(s.streams.begin(), s.streams.end());
  return s;
}

}  // namespace modd::link
