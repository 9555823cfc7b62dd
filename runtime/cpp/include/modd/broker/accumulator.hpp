// A running aggregate for one scheduled stream, updated on ingest and taken
// (value + reset) when the stream's window closes. An empty window gives an
// absent value. MEDIAN and PERCENTILE(p) keep the window's samples (at most kMaxAll, as ALL:
// validation refuses a subscription whose window may hold more); STDDEV is
// Welford's running population deviation (of the samples less the first); RANGE keeps the extremes.
#pragma once
#include <cstdint>
#include <limits>
#include <vector>

#include "modd/link/messages.hpp"

namespace modd::broker {

class Accumulator {
 public:
  static constexpr size_t kMaxAll = 65535;  // ALL keeps at most this many samples per window

  // `p`: PERCENTILE's, 0..100 (CONFIG checked it); unused by the others.
  Accumulator(link::ValueType type, link::Aggregation aggregation, double p = 0)
      : type_(type), agg_(aggregation), p_(p) {}
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
  double p_;
  uint64_t n_ = 0;
  double d_ = 0, dsum_ = 0;
  int64_t i_ = 0, isum_ = 0;
  double mean_ = 0, m2_ = 0, shift_ = 0;  // STDDEV (Welford, shifted)
  double dlo_ = 0;                        // RANGE of float topics: d_ is the largest
  int64_t ilo_ = 0;                       // RANGE of int topics: i_ is the largest
  std::vector<double> samples_;           // MEDIAN, PERCENTILE
  link::Value all_;
  void add_statistic(double x, int64_t integer, bool first);
  double take_statistic();
};

// numpy.percentile(samples, p) with its default method "linear", to the bit: the
// sorted samples' value at the virtual index (n - 1) * p / 100, between its two
// neighbours as numpy interpolates them (from the upper one when the fraction is at
// least a half). O(n): reorders `samples` (nth_element). Throws std::invalid_argument
// for no sample or p outside [0, 100].
double percentile(std::vector<double>& samples, double p);

}  // namespace modd::broker
