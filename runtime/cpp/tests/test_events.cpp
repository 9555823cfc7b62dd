// The event detector against the contract's vectors (contracts/vectors/events.json,
// written by the reference definition modd_contracts.events), and its bounds.
#include <gtest/gtest.h>

#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "modd/broker/events.hpp"

using namespace modd::broker;
namespace ev = modd::link::events;

namespace {
nlohmann::json event_vectors() {
  std::ifstream f(std::string(MODD_CONTRACTS_DIR) + "/vectors/events.json");
  return f.good() ? nlohmann::json::parse(f) : nlohmann::json();
}
EventSpec spec_of(const nlohmann::json& s) {
  EventSpec spec;
  spec.kind = static_cast<ev::EventKind>(s["kind"].get<int>());
  spec.max_events = s["maxEvents"].get<uint32_t>();
  spec.deadband = s["deadband"].get<double>();
  spec.mode = static_cast<ev::DeadbandMode>(s["mode"].get<int>());
  spec.level = s["level"].get<double>();
  spec.hysteresis = s["hysteresis"].get<double>();
  spec.crossing = static_cast<ev::Crossing>(s["crossing"].get<int>());
  return spec;
}
}  // namespace

TEST(EventDetector, WindowsEqualTheContractVectors) {
  auto doc = event_vectors();
  ASSERT_FALSE(doc.is_null()) << "contracts/vectors/events.json is missing";
  int64_t epoch = doc["epochNs"], period = doc["periodNs"];
  ASSERT_GE(doc["vectors"].size(), 40u);
  for (const auto& c : doc["vectors"]) {
    SCOPED_TRACE(c["name"].get<std::string>());
    EventDetector det(spec_of(c["spec"]));
    std::vector<EventWindow> got;
    int64_t end = epoch + period;
    got.emplace_back();
    for (const auto& s : c["samples"]) {
      int64_t t = s[0];
      while (t >= end) {  // the window closes before a later sample is added
        got.back() = det.take();
        got.emplace_back();
        end += period;
      }
      det.add(t, s[1].get<double>());
    }
    got.back() = det.take();
    const auto& want = c["windows"];
    ASSERT_EQ(got.size(), want.size());
    for (size_t j = 0; j < got.size(); ++j) {
      std::vector<Event> events;
      for (const auto& e : want[j]["events"]) events.push_back({e[0], e[1].get<double>()});
      EXPECT_EQ(got[j].events, events) << "window " << j;
      EXPECT_EQ(got[j].coalesced, want[j]["coalesced"].get<uint64_t>()) << "window " << j;
    }
  }
}

TEST(EventDetector, FlappingKeepsTheBoundAndCountsTheRest) {
  EventSpec spec;
  spec.kind = ev::EventKind::Threshold;
  spec.level = 5;
  spec.max_events = 2;
  EventDetector det(spec);
  for (int k = 0; k < 1001; ++k) det.add(k, k % 2 ? 4.0 : 6.0);
  auto w = det.take();
  ASSERT_EQ(w.events.size(), 2u);
  EXPECT_EQ(w.events[0], (Event{1, 4.0}));
  EXPECT_EQ(w.events[1], (Event{1000, 6.0}));  // the newest
  EXPECT_EQ(w.coalesced, 1000u - 2u);          // 1000 crossings in all
  EXPECT_EQ(det.coalesced_total(), 998u);
  EXPECT_TRUE(det.take().events.empty());
}

TEST(EventDetector, RefusesASpecOutOfBounds) {
  EventSpec spec;
  spec.max_events = 0;
  EXPECT_THROW(EventDetector{spec}, std::invalid_argument);
  spec.max_events = ev::kMaxEvents + 1;
  EXPECT_THROW(EventDetector{spec}, std::invalid_argument);
  spec.max_events = 3;
  spec.deadband = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(EventDetector{spec}, std::invalid_argument);
  spec.deadband = 0;
  spec.hysteresis = -1;
  EXPECT_THROW(EventDetector{spec}, std::invalid_argument);
}
