// CRC-32 (IEEE 802.3, the zlib one), as MCAP requires.
#pragma once
#include <cstdint>
#include <span>

namespace modd::archive {
// Continues a CRC: crc32(crc32(0, a), b) == crc32(0, a + b).
uint32_t crc32(uint32_t crc, std::span<const uint8_t> data);
}  // namespace modd::archive
