// The C++ subscriber client's parsing of delivered values: the backfilled mark
// (docs/subbroker.md, "Delivered value") is exposed, absent on live values.
#include <gtest/gtest.h>

#include "modd/client/subscriber.hpp"

TEST(SubscriberParse, BackfilledMark) {
  const std::string live =
      R"({"subscriber":"sub_5","topic":"usv.a.z","aggregation":"MIN","period_s":"0.25","unit":"M",)"
      R"("config_id":1,"slot":7,"start_ns":0,"end_ns":250000000,"value":-0.5,"count":null,)"
      R"("delivered_ns":1,"v":1})";
  modd::Delivered d;
  std::string err;
  ASSERT_TRUE(modd::parse_delivered(live, d, &err)) << err;
  EXPECT_FALSE(d.backfilled);
  std::string back = live;
  back.insert(back.size() - 1, R"(,"backfilled":true)");
  ASSERT_TRUE(modd::parse_delivered(back, d, &err)) << err;
  EXPECT_TRUE(d.backfilled);
  EXPECT_EQ(d.end_ns, 250000000);
  std::string bad = live;
  bad.insert(bad.size() - 1, R"(,"backfilled":1)");
  EXPECT_FALSE(modd::parse_delivered(bad, d, &err));
  EXPECT_NE(err.find("backfilled"), std::string::npos);
}
