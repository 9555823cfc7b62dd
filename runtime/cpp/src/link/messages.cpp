#include "modd/link/messages.hpp"

#include "modd/link/aggregation_table.gen.hpp"

namespace modd::link {

// The value types' labels (wire.gen.hpp) and the aggregation table and enum are
// generated from the metamodel (python -m modd_contracts.typegen), in wire-code order.

const char* value_type_name(ValueType t) {
  size_t i = static_cast<size_t>(t);
  return i < kValueTypeCount ? kValueTypeLabels[i] : "?";
}
const char* aggregation_name(Aggregation a) {
  int i = static_cast<int>(a);
  return i < table::kAggregationCount ? table::kAggregations[i].name : "?";
}

bool parse_value_type(const std::string& s, ValueType& out) {
  for (size_t i = 0; i < kValueTypeCount; ++i)
    if (s == kValueTypeLabels[i]) {
      out = static_cast<ValueType>(i);
      return true;
    }
  return false;
}
bool parse_aggregation(const std::string& s, Aggregation& out) {
  for (int i = 0; i < table::kAggregationCount; ++i)
    if (s == table::kAggregations[i].name) {
      out = static_cast<Aggregation>(i);
      return true;
    }
  return false;
}

ValueKind value_kind(ValueType type, Aggregation a, double resolution) {
  // The wire type of the value per topic type is the table's `result`; a COUNT,
  // never negative, is written as an unsigned varint rather than zigzag.
  if (a == Aggregation::Count) return {a, ScalarKind::UVarint};
  static constexpr ScalarKind kScalar[] = {ScalarKind::F32, ScalarKind::F64, ScalarKind::ZigZag,
                                           ScalarKind::Bool};
  int i = static_cast<int>(a);
  ScalarKind k = i >= table::kAggregationCount
                     ? kScalar[static_cast<int>(type) & 3]
                     : kScalar[table::kAggregations[i].result[static_cast<int>(type) & 3]];
  bool is_float = k == ScalarKind::F32 || k == ScalarKind::F64;
  return {a, k, is_float && !is_event(a) ? resolution : 0};  // events go exact
}

}  // namespace modd::link
