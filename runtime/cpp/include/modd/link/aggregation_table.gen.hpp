// Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit.
// The aggregation table (metamodel/modd.schema.json, Aggregation x-table).
#pragma once

#include <cstdint>

namespace modd::link {

// The wire code of each aggregation (docs/protocol.md).
enum class Aggregation : uint8_t {
  Min = 0,
  Max = 1,
  Average = 2,
  First = 3,
  Last = 4,
  All = 5,
  Count = 6,
  Sum = 7,
  Median = 8,
  Stddev = 9,
  Range = 10,
  Percentile = 11,
  OnChange = 12,
  Threshold = 13,
};

}  // namespace modd::link

namespace modd::link::table {

struct AggregationRow {
  const char* name;
  uint8_t code;
  bool numeric_only;
  bool wire_count;
  bool keeps_samples;  // holds every sample of the window (at most kMaxList)
  // Wire value type per topic type, indexed by ValueType
  // (float32, float64, int, bool): 0 float32, 1 float64, 2 int, 3 bool.
  uint8_t result[4];
};

inline constexpr AggregationRow kAggregations[] = {
    {"MIN", 0, false, false, false, {0, 1, 2, 3}},
    {"MAX", 1, false, false, false, {0, 1, 2, 3}},
    {"AVERAGE", 2, true, true, false, {0, 1, 1, 0}},
    {"FIRST", 3, false, false, false, {0, 1, 2, 3}},
    {"LAST", 4, false, false, false, {0, 1, 2, 3}},
    {"ALL", 5, false, false, true, {0, 1, 2, 3}},
    {"COUNT", 6, false, false, false, {2, 2, 2, 2}},
    {"SUM", 7, true, false, false, {0, 1, 2, 2}},
    {"MEDIAN", 8, true, false, true, {0, 1, 1, 0}},
    {"STDDEV", 9, true, false, false, {0, 1, 1, 0}},
    {"RANGE", 10, true, false, false, {0, 1, 2, 2}},
    {"PERCENTILE", 11, true, false, true, {0, 1, 1, 0}},
    {"ON_CHANGE", 12, false, false, false, {0, 1, 2, 3}},
    {"THRESHOLD", 13, true, false, false, {0, 1, 2, 3}},
};
inline constexpr int kAggregationCount = 14;

// Value types in the order of result[]: Float32, Float64, Int, Bool.

}  // namespace modd::link::table
