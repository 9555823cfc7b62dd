#include "modd/broker/accumulator.hpp"

#include <algorithm>

namespace modd::broker {

using link::Aggregation;

void Accumulator::add(double number, int64_t integer) {
  bool first = n_ == 0;
  ++n_;
  switch (agg_) {
    case Aggregation::Min:
      if (is_float())
        d_ = first ? number : std::min(d_, number);
      else
        i_ = first ? integer : std::min(i_, integer);
      break;
    case Aggregation::Max:
      if (is_float())
        d_ = first ? number : std::max(d_, number);
      else
        i_ = first ? integer : std::max(i_, integer);
      break;
    case Aggregation::First:
      if (first) {
        d_ = number;
        i_ = integer;
      }
      break;
    case Aggregation::Last:
      d_ = number;
      i_ = integer;
      break;
    case Aggregation::Average:
    case Aggregation::Sum:
      if (is_float())
        dsum_ += number;
      else
        isum_ += integer;  // wraps like int64 (documented)
      break;
    case Aggregation::Count: break;
    case Aggregation::All:
      if (is_float()) {
        if (all_.numbers.size() < kMaxAll) all_.numbers.push_back(number);
      } else if (all_.integers.size() < kMaxAll) {
        all_.integers.push_back(integer);
      }
      break;
  }
}

link::Value Accumulator::take() {
  link::Value v;
  v.present = n_ > 0;
  if (v.present) {
    switch (agg_) {
      case Aggregation::Min:
      case Aggregation::Max:
      case Aggregation::First:
      case Aggregation::Last:
        v.number = d_;
        v.integer = i_;
        break;
      case Aggregation::Average:
        v.number = is_float() ? dsum_ / static_cast<double>(n_)
                              : static_cast<double>(isum_) / static_cast<double>(n_);
        v.count = n_;
        break;
      case Aggregation::Sum:
        v.number = dsum_;
        v.integer = isum_;
        break;
      case Aggregation::Count: v.count = n_; break;
      case Aggregation::All:
        v = std::move(all_);
        v.present = true;
        v.count = n_;
        break;
    }
  }
  n_ = 0;
  d_ = dsum_ = 0;
  i_ = isum_ = 0;
  all_ = link::Value{};
  return v;
}

}  // namespace modd::broker
