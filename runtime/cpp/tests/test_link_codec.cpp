#include <gtest/gtest.h>

#include "modd/link/codec.hpp"
#include "modd/util/bytes.hpp"

using namespace modd;
using namespace modd::link;

namespace {
std::vector<uint8_t> enc(const Message& m) {
  std::vector<uint8_t> b;
  encode(b, m);
  return b;
}
Message dec(const std::vector<uint8_t>& b) {
  auto f = split_frame(b);
  EXPECT_TRUE(f);
  EXPECT_EQ(f->size, b.size());
  return decode(*f);
}
}  // namespace

TEST(LinkCodec, RoundTripEveryControlMessage) {
  Config c;
  c.config_id = 9;
  c.status_period_s = 17;
  c.topics = {{"a.b.c", ValueType::Float64, 1000, 40000}, {"x", ValueType::Bool, 1, 0}};
  c.streams = {{0, Aggregation::Sum, 1}, {1, Aggregation::All, 2'000'000'000}};
  std::vector<Message> msgs = {Hello{1, {1, 2, 3}},
                               Challenge{1, {9}},
                               Auth{{7}},
                               AuthOk{{1}, 3, 123456789},
                               Ping{{1, 2, 3}},
                               Pong{{}},
                               c,
                               ConfigAck{9, 0, 42},
                               Status{{0, 1, 300, 1ull << 40}},
                               Status{{5}, {{"gnss", {1, 2, 1ull << 40}}, {"ctd", {}}}},
                               ErrorMsg{3, "no"}};
  for (const auto& m : msgs) {
    auto b = enc(m);
    Message back = dec(b);
    EXPECT_EQ(back.index(), m.index());
    EXPECT_EQ(enc(back), b);
  }
  EXPECT_EQ(std::get<Config>(dec(enc(c))), c);
}

TEST(LinkCodec, StatusCarriesInstrumentHealthOnlyWhenThereIsSome) {
  Status with{{7, 8}, {{"gnss", {1, 300}}}};
  auto back = std::get<Status>(dec(enc(with)));
  EXPECT_EQ(back.counters, with.counters);
  EXPECT_EQ(back.sensors, with.sensors);
  // Without instruments the frame is the counters alone, as before.
  EXPECT_EQ(enc(Status{{7, 8}}), (std::vector<uint8_t>{0x04, 0x20, 0x02, 0x07, 0x08}));
  std::vector<uint8_t> empty_name = enc(Status{{7}, {{"x", {}}}});
  empty_name[5] = 0;  // the name's length
  empty_name.pop_back(), empty_name.pop_back();
  empty_name[0] = static_cast<uint8_t>(empty_name.size() - 1);
  EXPECT_THROW(dec(empty_name), Error);
}

TEST(LinkCodec, SplitNeedsWholeFrames) {
  auto b = enc(Ping{{1, 2, 3}});
  for (size_t n = 0; n < b.size(); ++n) EXPECT_FALSE(split_frame(std::span(b).first(n)));
  EXPECT_TRUE(split_frame(b));
  std::vector<uint8_t> big = {0x80, 0x80, 0x80, 0x01};  // 2 MiB announced
  EXPECT_THROW(split_frame(big), Error);
}

TEST(LinkCodec, DataSizesMatchTheFormula) {
  // Scenario 1: 2 AVERAGE float32 (4 + 1-byte count) + MIN + MAX float32 -> 21 bytes on the wire.
  std::vector<ValueKind> k = {value_kind(ValueType::Float32, Aggregation::Average),
                              value_kind(ValueType::Float32, Aggregation::Average),
                              value_kind(ValueType::Float32, Aggregation::Min),
                              value_kind(ValueType::Float32, Aggregation::Max)};
  Data d;
  d.seq8 = 3;
  for (int i = 0; i < 4; ++i) {
    Value v;
    v.present = true;
    v.number = i;
    v.count = 6;
    d.values.push_back(v);
  }
  std::vector<uint8_t> out;
  encode_data(out, d, k);
  EXPECT_EQ(out.size(), 21u);
  // Scenario 2: 19 MIN float32 -> 3 + 76 = 79 bytes.
  std::vector<ValueKind> k2(19, value_kind(ValueType::Float32, Aggregation::Min));
  Data d2;
  d2.values.assign(19, Value{true});
  out.clear();
  encode_data(out, d2, k2);
  EXPECT_EQ(out.size(), 79u);
  // One absent stream adds a bitmap byte and removes its value.
  d.values[1].present = false;
  out.clear();
  encode_data(out, d, k);
  EXPECT_EQ(out.size(), 21u - 5 + 1);
  EXPECT_EQ(out[1], 0x11);
}

TEST(LinkCodec, DataDecodeRejectsBadValues) {
  std::vector<ValueKind> k = {value_kind(ValueType::Bool, Aggregation::Last)};
  std::vector<uint8_t> bad_bool = {0x03, 0x10, 0x00, 0x02};
  EXPECT_THROW(decode_data(*split_frame(bad_bool), k), Error);
  std::vector<uint8_t> stray_bit = {0x04, 0x11, 0x00, 0x03, 0x01};
  EXPECT_THROW(decode_data(*split_frame(stray_bit), k), Error);
  std::vector<uint8_t> trailing = {0x04, 0x10, 0x00, 0x01, 0x01};
  EXPECT_THROW(decode_data(*split_frame(trailing), k), Error);
  std::vector<uint8_t> ok = {0x03, 0x10, 0x00, 0x01};
  EXPECT_EQ(decode_data(*split_frame(ok), k).values[0].integer, 1);
}

TEST(LinkCodec, ValueKinds) {
  EXPECT_EQ(value_kind(ValueType::Int, Aggregation::Average).scalar, ScalarKind::F64);
  EXPECT_EQ(value_kind(ValueType::Float32, Aggregation::Average).scalar, ScalarKind::F32);
  EXPECT_EQ(value_kind(ValueType::Bool, Aggregation::Sum).scalar, ScalarKind::ZigZag);
  EXPECT_EQ(value_kind(ValueType::Float64, Aggregation::Count).scalar, ScalarKind::UVarint);
  EXPECT_EQ(value_kind(ValueType::Int, Aggregation::Max).scalar, ScalarKind::ZigZag);
}
