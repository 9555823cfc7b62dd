#include <gtest/gtest.h>

#include <limits>

#include "modd/util/bytes.hpp"

using namespace modd;

TEST(Bytes, VarintRoundTripAndSizes) {
  for (uint64_t v :
       std::initializer_list<uint64_t>{0, 1, 127, 128, 300, 16383, 16384, (1ull << 35) + 7,
                                       std::numeric_limits<uint64_t>::max()}) {
    std::vector<uint8_t> b;
    ByteWriter w(b);
    w.varint(v);
    EXPECT_EQ(b.size(), varint_size(v));
    ByteReader r(b);
    EXPECT_EQ(r.varint(), v);
    EXPECT_TRUE(r.empty());
  }
}

TEST(Bytes, ZigZag) {
  for (int64_t v : {int64_t{0}, int64_t{-1}, int64_t{1}, int64_t{-70000},
                    std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::max()})
    EXPECT_EQ(zigzag_decode(zigzag_encode(v)), v);
  EXPECT_EQ(zigzag_encode(-1), 1u);
  EXPECT_EQ(zigzag_encode(1), 2u);
}

TEST(Bytes, ReaderErrorsCarryOffsets) {
  std::vector<uint8_t> b = {0x01, 0x80, 0x80};
  ByteReader r(b, 10);
  EXPECT_EQ(r.u8(), 1);
  try {
    r.varint();
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::BadFrame);
    EXPECT_EQ(e.offset(), 13u);
  }
  std::vector<uint8_t> over(11, 0xFF);
  ByteReader r2(over);
  EXPECT_THROW(r2.varint(), Error);
}

TEST(Bytes, Hex) {
  std::vector<uint8_t> b = {0x00, 0xAB, 0x10};
  EXPECT_EQ(to_hex(b), "00ab10");
  EXPECT_EQ(from_hex("00AB10"), b);
  EXPECT_THROW(from_hex("0"), Error);
  EXPECT_THROW(from_hex("zz"), Error);
}
