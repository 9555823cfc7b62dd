#include "modd/broker/accumulator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

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
    case Aggregation::Median:
    case Aggregation::Percentile:
    case Aggregation::Stddev:
    case Aggregation::Range: add_statistic(number, integer, first); break;
    case Aggregation::OnChange:
    case Aggregation::Threshold: break;  // an EventDetector's (broker/events.hpp)
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
      case Aggregation::Range:
        if (is_float())
          v.number = d_ - dlo_;
        else
          v.integer = static_cast<int64_t>(static_cast<uint64_t>(i_) -
                                           static_cast<uint64_t>(ilo_));  // wraps like SUM
        break;
      case Aggregation::Median:
      case Aggregation::Percentile:
      case Aggregation::Stddev: v.number = take_statistic(); break;
      case Aggregation::OnChange:
      case Aggregation::Threshold: v.present = false; break;
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
  mean_ = m2_ = shift_ = dlo_ = 0;
  ilo_ = 0;
  samples_.clear();
  all_ = link::Value{};
  return v;
}

void Accumulator::add_statistic(double number, int64_t integer, bool first) {
  double x = is_float() ? number : static_cast<double>(integer);
  switch (agg_) {
    case Aggregation::Median:
    case Aggregation::Percentile:
      if (samples_.size() < kMaxAll) samples_.push_back(x);
      break;
    case Aggregation::Stddev: {  // Welford on x - (the first sample): stable in one pass,
      if (first) shift_ = x;     // and precise far from zero (a pressure near 101325 Pa)
      x -= shift_;
      double delta = x - mean_;
      mean_ += delta / static_cast<double>(n_);
      m2_ += delta * (x - mean_);
      break;
    }
    default:  // Range
      if (is_float()) {
        d_ = first ? number : std::max(d_, number);
        dlo_ = first ? number : std::min(dlo_, number);
      } else {
        i_ = first ? integer : std::max(i_, integer);
        ilo_ = first ? integer : std::min(ilo_, integer);
      }
  }
}

// numpy.median (the mean of the two middle samples of an even count),
// numpy.percentile (linear) and numpy.std (ddof=0) of the window.
double Accumulator::take_statistic() {
  if (agg_ == Aggregation::Stddev) return std::sqrt(m2_ / static_cast<double>(n_));
  if (agg_ == Aggregation::Percentile) return percentile(samples_, p_);
  size_t mid = samples_.size() / 2;
  std::nth_element(samples_.begin(), samples_.begin() + static_cast<std::ptrdiff_t>(mid),
                   samples_.end());
  double upper = samples_[mid];
  if (samples_.size() % 2) return upper;
  double lower =
      *std::max_element(samples_.begin(), samples_.begin() + static_cast<std::ptrdiff_t>(mid));
  return (lower + upper) / 2;
}

double percentile(std::vector<double>& samples, double p) {
  if (samples.empty()) throw std::invalid_argument("percentile of no sample");
  if (!(p >= 0 && p <= 100)) throw std::invalid_argument("percentile p is not in [0, 100]");
  double index = static_cast<double>(samples.size() - 1) * (p / 100);
  auto lower = static_cast<size_t>(std::floor(index));
  auto at = samples.begin() + static_cast<std::ptrdiff_t>(lower);
  std::nth_element(samples.begin(), at, samples.end());
  double a = *at;
  if (lower + 1 >= samples.size()) return a;
  double b = *std::min_element(at + 1, samples.end());
  double t = index - static_cast<double>(lower);
  return t >= 0.5 ? b - (b - a) * (1 - t) : a + (b - a) * t;
}

}  // namespace modd::broker
