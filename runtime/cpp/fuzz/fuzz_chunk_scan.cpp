// libFuzzer target: the scan of a damaged MCAP file that recovery trusts (chunk_scan.hpp) on
// arbitrary bytes. Must never crash, leak, hit UB or allocate past its bound; whatever it keeps
// must lie inside the file and add up.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "modd/archive/chunk_scan.hpp"

using namespace modd::archive;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::span<const uint8_t> file(data, size);
  for (bool index : {true, false}) {
    FileScan s = scan_mcap(file, index);
    uint64_t messages = 0, end = 0;
    for (const ScannedChunk& c : s.chunks) {
      if (c.ci.offset < end || c.ci.offset + c.ci.length > size) std::abort();
      end = c.ci.offset + c.ci.length;
      for (const auto& [ch, n] : c.counts) messages += n;
    }
    for (const Skipped& k : s.skipped)
      if (k.offset + k.length > size) std::abort();
    if (messages != s.messages || s.clean_end > size || s.clean_chunks > s.chunks.size())
      std::abort();
  }
  return 0;
}
