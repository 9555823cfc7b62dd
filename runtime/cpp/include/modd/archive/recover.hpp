// Recovery of MCAP files left unfinished by a crash (kill -9, power cut, a stop with the disk
// full): every chunk whose data checks is kept, wherever it lies (a damaged chunk or record is
// skipped, not a stop: chunk_scan.hpp), its Message Index records rewritten if they were torn
// or damaged, and the file gets Data End, summary and footer, so that every reader opens it.
// When nothing trusted lies past the damage (a torn tail: the usual crash) the file is cut
// there and finished in place, needing room for the summary only (a few KiB). Otherwise the
// kept records are written beside it (`.recovering`), read back, and renamed over it: the
// original is never cut while a trusted record lies past the cut. A crash or a full disk
// meanwhile leaves the original (and a stale `.recovering`, removed at the next attempt).
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "modd/archive/chunk_scan.hpp"
#include "modd/archive/mcap_writer.hpp"

namespace modd::archive {

struct Recovered {
  std::string path;
  uint64_t messages = 0;          // kept
  uint64_t chunks = 0;            // kept
  uint64_t rewritten_chunks = 0;  // kept, written anew from their data (ScannedChunk::reencode)
  uint64_t dropped_bytes = 0;     // damaged regions and torn tail
  std::vector<Skipped> skipped;   // the damaged regions (offset, length, why), in file order
  bool rewritten = false;  // written beside and renamed over (a trusted record lay past damage)
  bool removed = false;    // empty file (nothing but a partial magic/header): removed
  bool foreign = false;    // no magic and no record found: left as it is
  bool failed = false;     // could not be finished (e.g. disk full): to be tried again
};

// Decompresses one chunk's records ("", "zstd" or "lz4") into out (exactly `size` bytes).
bool decompress_chunk(const std::string& compression, std::span<const uint8_t> in, uint64_t size,
                      std::vector<uint8_t>& out);
// True if the file ends with the MCAP magic (it was closed).
bool mcap_complete(const std::string& path);
// Recovers one file. Throws Error if it cannot be read or finished (the original then stays).
Recovered recover_mcap(const std::string& path, const WriterOptions& options);
// The log lines of one recovery (kept and dropped, then each skipped region); `when` follows
// the file's name (e.g. " now that there is room").
void log_recovered(const std::string& name, const Recovered& r, const char* when = "");
// Recovers every `<prefix>*.mcap` file of `dir` that is not complete (and removes stale
// `.recovering` files an older version's interrupted recovery left). Errors are logged, not
// thrown: a file that could not be finished is returned with `failed` set.
std::vector<Recovered> recover_dir(const std::string& dir, const std::string& prefix,
                                   const WriterOptions& options);

}  // namespace modd::archive
