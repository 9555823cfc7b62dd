// The contracts (contracts/vectors, docs/architecture.md "Contracts") as C++
// reads them: the subscriber client parses every delivered-value vector the
// SubBroker writes, and the link's aggregation names are the generated table's.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "modd/client/subscriber.hpp"
#include "modd/link/aggregation_table.gen.hpp"
#include "modd/link/messages.hpp"

using nlohmann::json;

namespace {

json vectors(const std::string& name) {
  std::ifstream f(std::string(MODD_CONTRACTS_DIR) + "/vectors/" + name + ".json");
  EXPECT_TRUE(f.good()) << name;
  return json::parse(f);
}

}  // namespace

TEST(Contracts, SubscriberParsesEveryDeliveredValue) {
  json v = vectors("delivered_value");
  ASSERT_FALSE(v["vectors"].empty());
  for (const auto& c : v["vectors"]) {
    std::string line = c["line"].get<std::string>();
    json doc = json::parse(line);
    modd::Delivered d;
    std::string error;
    ASSERT_TRUE(modd::parse_delivered(line, d, &error)) << c["name"] << ": " << error;
    EXPECT_EQ(d.subscriber, doc["subscriber"].get<std::string>());
    EXPECT_EQ(d.topic, doc["topic"].get<std::string>());
    EXPECT_EQ(d.aggregation, doc["aggregation"].get<std::string>());
    EXPECT_EQ(d.period_s, doc["period_s"].get<std::string>());
    EXPECT_EQ(d.unit, doc["unit"].get<std::string>());
    EXPECT_EQ(d.config_id, doc["config_id"].get<uint64_t>());
    EXPECT_EQ(d.slot, doc["slot"].get<uint64_t>());
    EXPECT_EQ(d.start_ns, doc["start_ns"].get<int64_t>());
    EXPECT_EQ(d.end_ns, doc["end_ns"].get<int64_t>());
    EXPECT_EQ(d.delivered_ns, doc["delivered_ns"].get<int64_t>());
    EXPECT_EQ(d.count, doc["count"].is_null() ? -1 : doc["count"].get<int64_t>()) << c["name"];
    const auto& samples = c["samples"];
    EXPECT_EQ(d.present, !samples.empty()) << c["name"];
    if (doc["value"].is_array()) {
      ASSERT_EQ(d.values.size(), samples.size()) << c["name"];
      for (size_t i = 0; i < samples.size(); ++i) EXPECT_DOUBLE_EQ(d.values[i], samples[i][1].get<double>());
    } else if (!samples.empty()) {
      EXPECT_DOUBLE_EQ(d.value, samples[0][1].get<double>()) << c["name"];
    }
  }
}

TEST(Contracts, AggregationNamesAreTheTables) {
  for (int i = 0; i < modd::link::table::kAggregationCount; ++i) {
    const auto& row = modd::link::table::kAggregations[i];
    EXPECT_EQ(row.code, i);
    auto a = static_cast<modd::link::Aggregation>(i);
    EXPECT_STREQ(modd::link::aggregation_name(a), row.name);
    modd::link::Aggregation parsed{};
    ASSERT_TRUE(modd::link::parse_aggregation(row.name, parsed));
    EXPECT_EQ(parsed, a);
  }
}
