#include <gtest/gtest.h>

#include <chrono>

#include "modd/link/schedule.hpp"

using namespace modd::link;

TEST(Schedule, Scenario1IsOneSlotEveryQuarterSecond) {
  std::vector<uint64_t> p = {250000, 250000, 250000, 250000};
  SlotIterator it(p);
  for (uint64_t k = 0; k < 16; ++k) {
    Slot s = it.next();
    EXPECT_EQ(s.index, k);
    EXPECT_EQ(s.offset_us, (k + 1) * 250000);
    EXPECT_EQ(s.streams, (std::vector<uint32_t>{0, 1, 2, 3}));
  }
}

TEST(Schedule, MergesDueDatesOfDifferentPeriods) {
  std::vector<uint64_t> p = {2'000'000, 500'000, 750'000};
  SlotIterator it(p);
  // dates: 0.5 {1}, 0.75 {2}, 1.0 {1}, 1.5 {1,2}, 2.0 {0,1}, 2.25 {2}
  std::vector<std::pair<uint64_t, std::vector<uint32_t>>> want = {
      {500000, {1}},     {750000, {2}},     {1000000, {1}},
      {1500000, {1, 2}}, {2000000, {0, 1}}, {2250000, {2}}};
  for (const auto& [t, ids] : want) {
    EXPECT_EQ(it.peek_offset_us(), t);
    Slot s = it.next();
    EXPECT_EQ(s.offset_us, t);
    EXPECT_EQ(s.streams, ids);
  }
}

TEST(Schedule, HugeHyperperiodIsNeverMaterialised) {
  // Coprime periods: the hyperperiod is ~31 years; the iterator is still instant.
  std::vector<uint64_t> p = {1'000'003, 999'983, 2'000'000};
  SlotIterator it(p);
  auto t0 = std::chrono::steady_clock::now();
  uint64_t last = 0;
  for (int i = 0; i < 100000; ++i) {
    Slot s = it.next();
    EXPECT_GT(s.offset_us, last);
    last = s.offset_us;
  }
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(2));
}

TEST(Schedule, EmptyAndZero) {
  std::vector<uint64_t> none;
  SlotIterator it(none);
  EXPECT_TRUE(it.empty());
  std::vector<uint64_t> zero = {0};
  EXPECT_ANY_THROW(SlotIterator{zero});
}
