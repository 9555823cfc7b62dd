#include "modd/archive/crc32.hpp"

#include <array>

namespace modd::archive {

namespace {
// Slicing-by-4 tables.
struct Tables {
  std::array<std::array<uint32_t, 256>, 4> t{};
  Tables() {
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[0][i] = c;
    }
    for (uint32_t i = 0; i < 256; ++i)
      for (int s = 1; s < 4; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xFF];
  }
};
const Tables& tables() {
  static const Tables tb;
  return tb;
}
}  // namespace

uint32_t crc32(uint32_t crc, std::span<const uint8_t> data) {
  const auto& t = tables().t;
  uint32_t c = ~crc;
  size_t i = 0, n = data.size();
  const uint8_t* p = data.data();
  for (; i + 4 <= n; i += 4) {
    c ^= static_cast<uint32_t>(p[i]) | static_cast<uint32_t>(p[i + 1]) << 8 |
         static_cast<uint32_t>(p[i + 2]) << 16 | static_cast<uint32_t>(p[i + 3]) << 24;
    c = t[3][c & 0xFF] ^ t[2][(c >> 8) & 0xFF] ^ t[1][(c >> 16) & 0xFF] ^ t[0][c >> 24];
  }
  for (; i < n; ++i) c = t[0][(c ^ p[i]) & 0xFF] ^ (c >> 8);
  return ~c;
}

}  // namespace modd::archive
