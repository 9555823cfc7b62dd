#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "modd/ingress/codec.hpp"

using namespace modd;
using namespace modd::ingress;

namespace {
struct Collect : Handler {
  std::vector<Register> regs;
  std::vector<Record> recs;
  std::string pub;
  void on_hello(const Hello& h) override { pub = h.publisher; }
  void on_register(const Register& r) override { regs.push_back(r); }
  bool type_of(uint32_t id, ValueType& t) const override {
    for (const auto& r : regs)
      if (r.local_id == id) {
        t = r.type;
        return true;
      }
    return false;
  }
  void on_record(const Record& r) override { recs.push_back(r); }
};

void feed(const std::vector<uint8_t>& b, Handler& h) {
  size_t at = 0;
  while (auto f = split_frame(std::span(b).subspan(at))) {
    at += f->size;
    decode(*f, h);
  }
  EXPECT_EQ(at, b.size());
}
}  // namespace

TEST(Ingress, RoundTripOfEveryType) {
  std::vector<uint8_t> b;
  encode_hello(b, {kVersion, "pub_1"});
  encode_register(b, {0, ValueType::Float32, "a"});
  encode_register(b, {1, ValueType::Float64, "b"});
  encode_register(b, {2, ValueType::Int, "c"});
  encode_register(b, {3, ValueType::Bool, "d"});
  std::vector<Record> rs = {
      {0, 10, 1.5, 0}, {1, 11, 1e-300, 0}, {2, 12, 0, -5}, {3, 13, 0, 1}, {0, -1, -0.25, 0}};
  ValueType types[] = {ValueType::Float32, ValueType::Float64, ValueType::Int, ValueType::Bool};
  encode_samples(b, rs, [&](uint32_t id) { return types[id]; });
  Collect c;
  feed(b, c);
  EXPECT_EQ(c.pub, "pub_1");
  ASSERT_EQ(c.recs.size(), rs.size());
  for (size_t i = 0; i < rs.size(); ++i) {
    EXPECT_EQ(c.recs[i].local_id, rs[i].local_id);
    EXPECT_EQ(c.recs[i].timestamp_ns, rs[i].timestamp_ns);
    EXPECT_EQ(c.recs[i].number, rs[i].number);
    EXPECT_EQ(c.recs[i].integer, rs[i].integer);
  }
}

TEST(Ingress, UnregisteredIdIsAnErrorWithRecordsLeft) {
  std::vector<uint8_t> b;
  encode_register(b, {0, ValueType::Float32, "a"});
  std::vector<Record> rs = {{0, 1, 1, 0}, {0, 2, 2, 0}, {5, 3, 3, 0}};
  encode_samples(b, rs, [](uint32_t) { return ValueType::Float32; });
  Collect c;
  size_t at = 0;
  auto f1 = split_frame(b);
  decode(*f1, c);
  at += f1->size;
  auto f2 = split_frame(std::span(b).subspan(at));
  uint64_t left = 0;
  EXPECT_THROW(decode(*f2, c, &left), Error);
  EXPECT_EQ(c.recs.size(), 2u);  // delivered before the error
  EXPECT_EQ(left, 1u);
}

TEST(Ingress, RejectsBadFrames) {
  Collect c;
  std::vector<std::vector<uint8_t>> bad = {
      {0x02, 0x01, 0x07},              // HELLO version 7
      {0x04, 0x02, 0x00, 0x09, 0x00},  // REGISTER type 9
      {0x04, 0x02, 0x00, 0x00, 0x00},  // REGISTER with an empty name
      {0x03, 0x03, 0x7F, 0x00},        // SAMPLES announcing 127 records in 1 byte
      {0x01, 0x09},                    // unknown type
  };
  for (const auto& b : bad) {
    auto f = split_frame(b);
    ASSERT_TRUE(f);
    EXPECT_THROW(decode(*f, c), Error);
  }
}

// The shared vectors (contracts/vectors/ingress/replies.json, written by the Python codec).
TEST(IngressVectors, RepliesDecodeAndEncodeByteForByte) {
  std::ifstream f(std::string(MODD_VECTORS_DIR) + "/../ingress/replies.json");
  ASSERT_TRUE(f);
  auto vectors = nlohmann::json::parse(f);
  struct H : modd::ingress::ReplyHandler {
    std::vector<uint8_t> again;
    void on_catalogue(const modd::ingress::Catalogue& c) override {
      modd::ingress::encode_catalogue(again, c);
    }
    void on_ack(const modd::ingress::Ack& a) override { modd::ingress::encode_ack(again, a); }
    void on_reject(const modd::ingress::RejectMsg& r) override {
      modd::ingress::encode_reject(again, r);
    }
  };
  size_t n = 0;
  for (const auto& v : vectors) {
    std::string hex = v["hex"];
    std::vector<uint8_t> wire;
    for (size_t i = 0; i + 1 < hex.size(); i += 2)
      wire.push_back(static_cast<uint8_t>(std::stoi(hex.substr(i, 2), nullptr, 16)));
    const auto& m = v["message"];
    if (m["type"] == "HELLO") {
      std::vector<uint8_t> out;
      modd::ingress::encode_hello(
          out, {static_cast<uint8_t>(m["version"].get<int>()), m["publisher"].get<std::string>()});
      EXPECT_EQ(out, wire);
      ++n;
      continue;
    }
    auto fr = modd::ingress::split_frame(wire, modd::ingress::kMaxFrame);
    ASSERT_TRUE(fr);
    struct Check : H {
      const nlohmann::json* m;
      void on_catalogue(const modd::ingress::Catalogue& c) override {
        EXPECT_EQ(c.drone, (*m)["drone"]);
        EXPECT_EQ(c.max_future_ms, (*m)["max_future_ms"]);
        EXPECT_EQ(c.max_past_ms, (*m)["max_past_ms"]);
        ASSERT_EQ(c.topics.size(), (*m)["topics"].size());
        EXPECT_EQ(c.topics[0].name, (*m)["topics"][0][0]);
        H::on_catalogue(c);
      }
      void on_ack(const modd::ingress::Ack& a) override {
        EXPECT_EQ(a.received, (*m)["received"]);
        EXPECT_EQ(a.settled, (*m)["settled"]);
        EXPECT_EQ(a.archived, (*m)["archived"]);
        H::on_ack(a);
      }
      void on_reject(const modd::ingress::RejectMsg& r) override {
        EXPECT_EQ(r.reason, (*m)["reason"]);
        EXPECT_EQ(r.count, (*m)["count"]);
        EXPECT_EQ(r.detail, (*m)["detail"]);
        H::on_reject(r);
      }
    } h;
    h.m = &m;
    modd::ingress::decode_reply(*fr, h);
    EXPECT_EQ(h.again, wire) << v["name"];
    ++n;
  }
  EXPECT_EQ(n, 4u);
}
