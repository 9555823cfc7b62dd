// The contracts (contracts/vectors, docs/architecture.md "Contracts") as C++
// reads them: the subscriber client parses every delivered-value vector the
// SubBroker writes, and the link's aggregation names are the generated table's.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "modd/archive/archive_record.gen.hpp"
#include "modd/archive/archiver.hpp"
#include "modd/archive/mcap_writer.hpp"
#include "modd/archive/reader.hpp"
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
      for (size_t i = 0; i < samples.size(); ++i)
        EXPECT_DOUBLE_EQ(d.values[i], samples[i][1].get<double>());
    } else if (!samples.empty()) {
      EXPECT_DOUBLE_EQ(d.value, samples[0][1].get<double>()) << c["name"];
    }
  }
}

// The repeats (delivered_value.json, "repeats"): a window whose identity came
// before is dropped, as the Python subscriber API and the backend drop it.
TEST(Contracts, SubscriberKeepsEachWindowOnce) {
  json v = vectors("delivered_value");
  ASSERT_FALSE(v["repeats"]["sequence"].empty());
  modd::SeenWindows seen;
  for (const auto& c : v["repeats"]["sequence"]) {
    std::string line = c["line"].get<std::string>();
    json doc = json::parse(line);
    modd::Delivered d;
    std::string error;
    ASSERT_TRUE(modd::parse_delivered(line, d, &error)) << c["name"] << ": " << error;
    EXPECT_EQ(d.has_identity, doc.contains("window")) << c["name"];
    if (d.has_identity) {
      EXPECT_EQ(d.drone, doc["drone"].get<std::string>());
      EXPECT_EQ(d.epoch_ns, doc["epoch_ns"].get<int64_t>());
      EXPECT_EQ(d.window, doc["window"].get<int64_t>());
    }
    EXPECT_EQ(seen.first(d), c["first"].get<bool>()) << c["name"];
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

// The archive record (contracts/vectors/archive_record.json): the archiver writes each
// vector's bytes and channel schema, and the archive reader reads each value back.
namespace {

modd::link::ValueType value_type(const std::string& name) {
  modd::link::ValueType t{};
  EXPECT_TRUE(modd::link::parse_value_type(name, t)) << name;
  return t;
}

// The vector's value as the broker holds it (non-finite floats are spelled as strings).
modd::archive::Sample sample_of(const json& v) {
  modd::archive::Sample s{1, 1, 0, 0};
  if (v.is_string()) {
    std::string w = v.get<std::string>();
    s.number = w == "nan" ? std::nan("") : w == "inf" ? HUGE_VAL : -HUGE_VAL;
  } else if (v.is_boolean()) {
    s.integer = v.get<bool>() ? 1 : 0;
  } else if (v.is_number_integer()) {
    s.integer = v.get<int64_t>();
    s.number = v.get<double>();
  } else {
    s.number = v.get<double>();
  }
  return s;
}

}  // namespace

TEST(Contracts, ArchiverWritesEveryArchiveRecord) {
  json v = vectors("archive_record");
  ASSERT_FALSE(v["records"].empty());
  for (const auto& c : v["channels"]) {
    auto t = value_type(c["type"].get<std::string>());
    EXPECT_EQ(modd::archive::sample_json_schema(t), c["schema_data"].get<std::string>())
        << c["type"];
    EXPECT_EQ(std::string(modd::archive_record::kSchemaPrefix) + modd::link::value_type_name(t),
              c["schema_name"].get<std::string>());
    EXPECT_EQ(modd::archive_record::kSchemaEncoding, c["schema_encoding"].get<std::string>());
    EXPECT_EQ(modd::archive_record::kMessageEncoding, c["message_encoding"].get<std::string>());
  }
  for (const auto& c : v["records"]) {
    std::string out;
    modd::archive::format_sample_json(out, value_type(c["type"].get<std::string>()),
                                      sample_of(c["value"]));
    EXPECT_EQ(out, c["data"].get<std::string>()) << c["name"];
  }
}

TEST(Contracts, ArchiveReaderReadsEveryArchiveRecord) {
  json v = vectors("archive_record");
  auto dir =
      std::filesystem::temp_directory_path() / ("modd-contracts-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  for (const auto& c : v["records"]) {
    std::string name = c["name"].get<std::string>();
    auto t = value_type(c["type"].get<std::string>());
    std::string data = c["data"].get<std::string>();
    {
      modd::archive::McapWriter w((dir / (name + "-0.mcap")).string(),
                                  modd::archive::WriterOptions{});
      uint16_t schema = w.add_schema("modd." + c["type"].get<std::string>(), "jsonschema",
                                     modd::archive::sample_json_schema(t));
      uint16_t ch = w.add_channel(schema, "d.s." + name, "json");
      w.add_message(ch, 0, 5, 5,
                    std::span(reinterpret_cast<const uint8_t*>(data.data()), data.size()));
      w.close();
    }
    modd::archive::TopicReader r(dir.string(), name, "d.s." + name, t);
    auto got = r.peek(0);
    ASSERT_TRUE(got.has_value()) << name;
    modd::archive::Sample want = sample_of(c["value"]);
    if (t == modd::link::ValueType::Int || t == modd::link::ValueType::Bool) {
      EXPECT_EQ(got->integer, want.integer) << name;
    } else if (std::isnan(want.number)) {
      EXPECT_TRUE(std::isnan(got->number)) << name;
    } else {
      double expect = t == modd::link::ValueType::Float32
                          ? static_cast<double>(static_cast<float>(want.number))
                          : want.number;
      EXPECT_EQ(got->number, expect) << name;
    }
  }
  std::filesystem::remove_all(dir);
}
