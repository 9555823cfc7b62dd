#include "modd/archive/crc32.hpp"

#include <array>
#include <cstring>

namespace modd::archive {

namespace {
// Slicing-by-16 (16 table lookups per 16 bytes, no data dependency between them):
// the archive writer checksums every chunk it writes, so this sits on the ingest path.
constexpr int kSlices = 16;

struct Tables {
  std::array<std::array<uint32_t, 256>, kSlices> t{};
  Tables() {
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[0][i] = c;
    }
    for (uint32_t i = 0; i < 256; ++i)
      for (int s = 1; s < kSlices; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xFF];
  }
};
const Tables& tables() {
  static const Tables tb;
  return tb;
}

uint32_t load_le32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 |
         static_cast<uint32_t>(p[2]) << 16 | static_cast<uint32_t>(p[3]) << 24;
}
}  // namespace

uint32_t crc32(uint32_t crc, std::span<const uint8_t> data) {
  const auto& t = tables().t;
  uint32_t c = ~crc;
  size_t i = 0, n = data.size();
  const uint8_t* p = data.data();
  for (; i + 16 <= n; i += 16) {
    const uint32_t a = load_le32(p + i) ^ c, b = load_le32(p + i + 4), d = load_le32(p + i + 8),
                   e = load_le32(p + i + 12);
    c = t[15][a & 0xFF] ^ t[14][(a >> 8) & 0xFF] ^ t[13][(a >> 16) & 0xFF] ^ t[12][a >> 24] ^
        t[11][b & 0xFF] ^ t[10][(b >> 8) & 0xFF] ^ t[9][(b >> 16) & 0xFF] ^ t[8][b >> 24] ^
        t[7][d & 0xFF] ^ t[6][(d >> 8) & 0xFF] ^ t[5][(d >> 16) & 0xFF] ^ t[4][d >> 24] ^
        t[3][e & 0xFF] ^ t[2][(e >> 8) & 0xFF] ^ t[1][(e >> 16) & 0xFF] ^ t[0][e >> 24];
  }
  for (; i < n; ++i) c = t[0][(c ^ p[i]) & 0xFF] ^ (c >> 8);
  return ~c;
}

}  // namespace modd::archive
