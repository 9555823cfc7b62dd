#include "modd/link/messages.hpp"

namespace modd::link {

namespace {
constexpr const char* kTypeNames[] = {"float32", "float64", "int", "bool"};
constexpr const char* kAggNames[] = {"MIN", "MAX", "AVERAGE", "FIRST", "LAST", "ALL", "COUNT", "SUM"};
}  // namespace

const char* value_type_name(ValueType t) { return kTypeNames[static_cast<int>(t) & 3]; }
const char* aggregation_name(Aggregation a) { return kAggNames[static_cast<int>(a) & 7]; }

bool parse_value_type(const std::string& s, ValueType& out) {
  for (int i = 0; i < 4; ++i)
    if (s == kTypeNames[i]) { out = static_cast<ValueType>(i); return true; }
  return false;
}
bool parse_aggregation(const std::string& s, Aggregation& out) {
  for (int i = 0; i < 8; ++i)
    if (s == kAggNames[i]) { out = static_cast<Aggregation>(i); return true; }
  return false;
}

ValueKind value_kind(ValueType type, Aggregation a) {
  ScalarKind natural = type == ValueType::Float32   ? ScalarKind::F32
                       : type == ValueType::Float64 ? ScalarKind::F64
                       : type == ValueType::Int     ? ScalarKind::ZigZag
                                                    : ScalarKind::Bool;
  switch (a) {
    case Aggregation::Min: case Aggregation::Max: case Aggregation::First:
    case Aggregation::Last: case Aggregation::All:
      return {a, natural};
    case Aggregation::Average:
      return {a, (type == ValueType::Float32 || type == ValueType::Bool) ? ScalarKind::F32 : ScalarKind::F64};
    case Aggregation::Sum:
      return {a, type == ValueType::Float32   ? ScalarKind::F32
                 : type == ValueType::Float64 ? ScalarKind::F64
                                              : ScalarKind::ZigZag};
    case Aggregation::Count:
      return {a, ScalarKind::UVarint};
  }
  return {a, natural};
}

}  // namespace modd::link
