// Recovery of MCAP files left unfinished by a crash (kill -9, power cut, a stop with the disk
// full): every complete chunk whose CRC holds (with its message indexes) is kept, the torn
// tail is dropped, and the file is finished in place: cut after its last complete record,
// then Data End, summary and footer appended, so that every reader opens it. It needs room
// for the summary only (a few KiB), not for a copy; a crash or a full disk meanwhile leaves a
// file that the next attempt scans to the same point.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "modd/archive/mcap_writer.hpp"

namespace modd::archive {

struct Recovered {
  std::string path;
  uint64_t messages = 0;       // kept
  uint64_t chunks = 0;         // kept
  uint64_t dropped_bytes = 0;  // torn tail (a chunk cut short or with a bad CRC, and what follows)
  bool removed = false;        // empty file (nothing but a partial magic/header): removed
  bool failed = false;         // could not be finished (e.g. disk full): to be tried again
};

// Decompresses one chunk's records ("", "zstd" or "lz4") into out (exactly `size` bytes).
bool decompress_chunk(const std::string& compression, std::span<const uint8_t> in, uint64_t size,
                      std::vector<uint8_t>& out);
// True if the file ends with the MCAP magic (it was closed).
bool mcap_complete(const std::string& path);
// Recovers one file in place. Throws Error(Io) if it cannot be read or rewritten.
Recovered recover_mcap(const std::string& path, const WriterOptions& options);
// Recovers every `<prefix>*.mcap` file of `dir` that is not complete (and removes stale
// `.recovering` files an older version's interrupted recovery left). Errors are logged, not
// thrown: a file that could not be finished is returned with `failed` set.
std::vector<Recovered> recover_dir(const std::string& dir, const std::string& prefix, const WriterOptions& options);

}  // namespace modd::archive
