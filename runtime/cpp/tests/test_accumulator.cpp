#include <gtest/gtest.h>

#include "modd/broker/accumulator.hpp"

using namespace modd::broker;
using modd::link::Aggregation;
using modd::link::ValueType;

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
