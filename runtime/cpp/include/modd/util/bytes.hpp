// Byte writer and reader: LEB128 varints, zigzag, little-endian fixed-width
// values and length-prefixed strings. The reader throws modd::Error
// (BadFrame) with the offset of the first byte it could not read.
#pragma once
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "modd/util/error.hpp"
#include "modd/util/varint.gen.hpp"  // kMaxVarintBytes (wire.json)

namespace modd {

inline uint64_t zigzag_encode(int64_t v) {
  return (static_cast<uint64_t>(v) << 1) ^ static_cast<uint64_t>(v >> 63);
}
inline int64_t zigzag_decode(uint64_t v) {
  return static_cast<int64_t>(v >> 1) ^ -static_cast<int64_t>(v & 1);
}
inline size_t varint_size(uint64_t v) {
  size_t n = 1;
  while (v >= 0x80) {
    v >>= 7;
    ++n;
  }
  return n;
}

class ByteWriter {
 public:
  explicit ByteWriter(std::vector<uint8_t>& out) : out_(out) {}
  void u8(uint8_t v) { out_.push_back(v); }
  void varint(uint64_t v) {
    while (v >= 0x80) {
      out_.push_back(static_cast<uint8_t>(v | 0x80));
      v >>= 7;
    }
    out_.push_back(static_cast<uint8_t>(v));
  }
  void svarint(int64_t v) { varint(zigzag_encode(v)); }
  template <typename T>
  void fixed(T v) {  // little-endian (the project targets little-endian hosts; checked in CMake)
    uint8_t b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    out_.insert(out_.end(), b, b + sizeof(T));
  }
  void bytes(std::span<const uint8_t> b) { out_.insert(out_.end(), b.begin(), b.end()); }
  void string(std::string_view s) {
    varint(s.size());
    out_.insert(out_.end(), s.begin(), s.end());
  }
  size_t size() const { return out_.size(); }
  std::vector<uint8_t>& buffer() { return out_; }

 private:
  std::vector<uint8_t>& out_;
};

class ByteReader {
 public:
  // base: offset of data[0] in the enclosing frame, for error messages.
  explicit ByteReader(std::span<const uint8_t> data, size_t base = 0) : d_(data), base_(base) {}
  size_t pos() const { return pos_; }
  size_t remaining() const { return d_.size() - pos_; }
  bool empty() const { return pos_ >= d_.size(); }
  uint8_t u8() {
    need(1);
    return d_[pos_++];
  }
  uint64_t varint() {
    uint64_t v = 0;
    for (int shift = 0; shift < 7 * kMaxVarintBytes; shift += 7) {
      need(1);
      uint8_t b = d_[pos_++];
      if (shift == 63 && b > 1) fail("varint overflows 64 bits");
      v |= static_cast<uint64_t>(b & 0x7F) << shift;
      if (!(b & 0x80)) return v;
    }
    fail("varint longer than " + std::to_string(kMaxVarintBytes) + " bytes");
  }
  int64_t svarint() { return zigzag_decode(varint()); }
  template <typename T>
  T fixed() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, d_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::span<const uint8_t> bytes(size_t n) {
    need(n);
    auto s = d_.subspan(pos_, n);
    pos_ += n;
    return s;
  }
  std::string string(size_t max_len = 4096) {
    uint64_t n = varint();
    if (n > max_len) fail("string longer than " + std::to_string(max_len));
    auto b = bytes(static_cast<size_t>(n));
    return std::string(b.begin(), b.end());
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(ErrorCode::BadFrame, what, base_ + pos_);
  }
  void expect_end() const {
    if (!empty()) fail(std::to_string(remaining()) + " trailing bytes");
  }

 private:
  void need(size_t n) const {
    if (d_.size() - pos_ < n) fail("truncated: need " + std::to_string(n) + " more bytes");
  }
  std::span<const uint8_t> d_;
  size_t pos_ = 0;
  size_t base_;
};

std::string to_hex(std::span<const uint8_t> b);
std::vector<uint8_t> from_hex(std::string_view hex);

}  // namespace modd
