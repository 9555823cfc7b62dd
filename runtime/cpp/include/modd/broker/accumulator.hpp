// A running aggregate for one scheduled stream, updated on ingest and taken
// (value + reset) when the stream's window closes. An empty window gives an
// absent value.
#pragma once
#include <cstdint>
#include <limits>

#include "modd/link/messages.hpp"

namespace modd::broker {

class Accumulator {
 public:
  static constexpr size_t kMaxAll = 65535;  // ALL keeps at most this many samples per window

  Accumulator(link::ValueType type, link::Aggregation aggregation)
      : type_(type), agg_(aggregation) {}
  // Float topics pass `number`, int and bool topics pass `integer`.
  void add(double number, int64_t integer);
  link::Value take();
  uint64_t count() const { return n_; }
  link::ValueType type() const { return type_; }
  link::Aggregation aggregation() const { return agg_; }

 private:
  bool is_float() const {
    return type_ == link::ValueType::Float32 || type_ == link::ValueType::Float64;
  }
  link::ValueType type_;
  link::Aggregation agg_;
  uint64_t n_ = 0;
  double d_ = 0, dsum_ = 0;
  int64_t i_ = 0, isum_ = 0;
  link::Value all_;
};

}  // namespace modd::broker
