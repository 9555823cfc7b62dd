#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "modd/broker/accumulator.hpp"

using namespace modd::broker;
using modd::link::Aggregation;
using modd::link::ValueType;

namespace {
// contracts/vectors/aggregations.json (numpy's values); null when it is missing.
nlohmann::json aggregation_vectors() {
  std::ifstream f(std::string(MODD_CONTRACTS_DIR) + "/vectors/aggregations.json");
  return f.good() ? nlohmann::json::parse(f) : nlohmann::json();
}
ValueType vector_type(const nlohmann::json& c) {
  if (c["type"] == "int") return ValueType::Int;
  return c["type"] == "float32" ? ValueType::Float32 : ValueType::Float64;
}
}  // namespace

TEST(Accumulator, FloatAggregates) {
  double xs[] = {3.0, -1.5, 7.25, 0.5};
  auto run = [&](Aggregation a) {
    Accumulator acc(ValueType::Float32, a);
    for (double x : xs) acc.add(x, 0);
    return acc.take();
  };
  EXPECT_EQ(run(Aggregation::Min).number, -1.5);
  EXPECT_EQ(run(Aggregation::Max).number, 7.25);
  EXPECT_EQ(run(Aggregation::First).number, 3.0);
  EXPECT_EQ(run(Aggregation::Last).number, 0.5);
  auto avg = run(Aggregation::Average);
  EXPECT_DOUBLE_EQ(avg.number, 9.25 / 4);
  EXPECT_EQ(avg.count, 4u);
  EXPECT_EQ(run(Aggregation::Sum).number, 9.25);
  EXPECT_EQ(run(Aggregation::Count).count, 4u);
  EXPECT_EQ(run(Aggregation::All).numbers, (std::vector<double>{3.0, -1.5, 7.25, 0.5}));
}

TEST(Accumulator, IntAggregatesAndReset) {
  Accumulator acc(ValueType::Int, Aggregation::Min);
  acc.add(0, 5);
  acc.add(0, -7);
  auto v = acc.take();
  EXPECT_TRUE(v.present);
  EXPECT_EQ(v.integer, -7);
  EXPECT_FALSE(acc.take().present);  // an empty window is absent
  acc.add(0, 9);
  EXPECT_EQ(acc.take().integer, 9);  // nothing of the previous window leaks
  Accumulator sum(ValueType::Int, Aggregation::Sum);
  sum.add(0, 1);
  sum.add(0, -70001);
  EXPECT_EQ(sum.take().integer, -70000);
  Accumulator avg(ValueType::Bool, Aggregation::Average);
  for (int b : {1, 0, 1, 1}) avg.add(0, b);
  EXPECT_DOUBLE_EQ(avg.take().number, 0.75);
}

// MEDIAN, STDDEV and RANGE equal numpy's over each window of the contract's
// vectors (contracts/vectors/aggregations.json, computed by numpy).
TEST(Accumulator, ExactStatisticsMatchNumpy) {
  auto doc = aggregation_vectors();
  ASSERT_FALSE(doc.is_null());
  ASSERT_GE(doc["vectors"].size(), 5u);
  for (const auto& c : doc["vectors"]) {
    bool is_int = c["type"] == "int";
    ValueType type = vector_type(c);
    auto run = [&](Aggregation a) {
      Accumulator acc(type, a);
      for (int round = 0; round < 2; ++round) {  // the second window starts clean
        for (const auto& x : c["samples"])
          acc.add(is_int ? 0.0 : x.get<double>(), is_int ? x.get<int64_t>() : 0);
        auto v = acc.take();
        EXPECT_TRUE(v.present);
        if (round == 1) return v;
      }
      return modd::link::Value{};
    };
    std::string name = c["name"];
    EXPECT_DOUBLE_EQ(run(Aggregation::Median).number, c["MEDIAN"].get<double>()) << name;
    double sd = c["STDDEV"].get<double>();
    EXPECT_NEAR(run(Aggregation::Stddev).number, sd, 1e-9 * sd + 1e-12) << name;
    if (is_int)
      EXPECT_EQ(run(Aggregation::Range).integer, c["RANGE"].get<int64_t>()) << name;
    else
      EXPECT_DOUBLE_EQ(run(Aggregation::Range).number, c["RANGE"].get<double>()) << name;
  }
}

// PERCENTILE(p) equals numpy.percentile (method "linear") to the bit over each window
// of the contract's vectors, for each p they carry; the samples' order does not matter.
TEST(Accumulator, PercentileMatchesNumpy) {
  auto doc = aggregation_vectors();
  ASSERT_FALSE(doc.is_null());
  size_t checked = 0;
  for (const auto& c : doc["vectors"]) {
    std::vector<double> window;
    for (const auto& x : c["samples"])
      window.push_back(c["type"] == "int" ? static_cast<double>(x.get<int64_t>())
                                          : x.get<double>());
    ASSERT_GE(c["PERCENTILE"].size(), 8u) << c["name"];
    for (const auto& [key, want] : c["PERCENTILE"].items()) {
      std::vector<double> samples = window;
      std::reverse(samples.begin(), samples.end());
      EXPECT_EQ(modd::broker::percentile(samples, std::stod(key)), want.get<double>())
          << c["name"] << " p=" << key;
      ++checked;
    }
  }
  EXPECT_GE(checked, 80u);
}

TEST(Accumulator, PercentileRefusesNoSampleAndPOutside0To100) {
  std::vector<double> none, two{1.0, 2.0};
  EXPECT_THROW(modd::broker::percentile(none, 50), std::invalid_argument);
  for (double p : {-1.0, 100.5, std::nan("")})
    EXPECT_THROW(modd::broker::percentile(two, p), std::invalid_argument) << p;
  EXPECT_EQ(modd::broker::percentile(two, 100), 2.0);
  EXPECT_EQ(modd::broker::percentile(two, 0), 1.0);  // numpy's: the minimum
}

// The PERCENTILE(p) accumulator (the PubBroker's, p from CONFIG) equals numpy's over
// each window of the contract's vectors, for each p they carry, two windows in a row.
TEST(Accumulator, PercentileAccumulatorMatchesNumpy) {
  auto doc = aggregation_vectors();
  ASSERT_FALSE(doc.is_null());
  size_t checked = 0;
  for (const auto& c : doc["vectors"]) {
    bool is_int = c["type"] == "int";
    ValueType type = vector_type(c);
    for (const auto& [key, want] : c["PERCENTILE"].items()) {
      Accumulator acc(type, Aggregation::Percentile, std::stod(key));
      for (int round = 0; round < 2; ++round) {
        for (const auto& x : c["samples"])
          acc.add(is_int ? 0.0 : x.get<double>(), is_int ? x.get<int64_t>() : 0);
        auto v = acc.take();
        ASSERT_TRUE(v.present);
        EXPECT_EQ(v.number, want.get<double>()) << c["name"] << " p=" << key;
      }
      ++checked;
    }
  }
  EXPECT_GE(checked, 80u);
  EXPECT_FALSE(Accumulator(ValueType::Float64, Aggregation::Percentile, 95).take().present);
}

TEST(Accumulator, StatisticsOfAnEmptyWindowAreAbsentAndMedianIsBounded) {
  for (auto a : {Aggregation::Median, Aggregation::Stddev, Aggregation::Range})
    EXPECT_FALSE(Accumulator(ValueType::Float64, a).take().present);
  Accumulator med(ValueType::Float64, Aggregation::Median);
  // beyond kMaxAll samples the median is over the window's first kMaxAll
  for (size_t i = 0; i < Accumulator::kMaxAll; ++i) med.add(1.0, 0);
  for (int i = 0; i < 1000; ++i) med.add(1e9, 0);
  auto v = med.take();
  EXPECT_EQ(v.number, 1.0);
}
