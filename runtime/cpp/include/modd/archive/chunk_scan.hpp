// A scan of an MCAP file that a crash or a bad byte damaged: every record it can trust, the
// damaged regions skipped (not a stop at the first one). A chunk is trusted when its header
// agrees with its record length, its data decompresses to the declared size (bounded) and its
// records match their CRC; past a damaged region the scan resyncs on the next record that
// checks whole (a chunk, or a schema or channel that parses exactly). A trusted chunk whose
// bytes are not the writer's for its data is marked to be written anew. Used by recovery
// (recover.hpp), which keeps what it trusts and reports what it skipped.
#pragma once
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "modd/archive/mcap_writer.hpp"

namespace modd::archive {

// Decompressed chunks larger than this are refused as a torn or crafted header.
constexpr uint64_t kMaxChunkBytes = 1ull << 28;

struct FileSpan {
  uint64_t offset = 0, length = 0;
};

struct ScannedChunk {
  ChunkIndex ci;                          // as found (offsets in the scanned file)
  std::map<uint16_t, uint64_t> counts;    // messages per channel
  std::vector<uint8_t> index;             // Message Index records to write after it
  std::map<uint16_t, uint64_t> index_at;  // channel -> offset of its record inside `index`
  bool index_intact = false;              // the file holds exactly `index` right after the chunk
  // Its data checks but its bytes are not what the writer makes of that data: a flip that a
  // lenient decoder reads past (libzstd 1.5.4 ignores reserved bits that 1.5.7 refuses), or
  // another writer's stream. Written anew from its data, so that every reader reads it.
  bool reencode = false;
};

struct Skipped {
  uint64_t offset = 0, length = 0;
  std::string why;
};

struct FileScan {
  bool magic = false;  // starts with the MCAP magic
  FileSpan header;     // length 0: none
  struct Schema {
    FileSpan at;
    std::string name, encoding, data;
  };
  struct Channel {
    FileSpan at;
    uint16_t schema = 0;
    std::string topic, encoding;
    std::map<std::string, std::string> meta;
  };
  std::map<uint16_t, Schema> schemas;
  std::map<uint16_t, Channel> channels;
  std::vector<ScannedChunk> chunks;
  std::vector<Skipped> skipped;  // damaged regions, in file order
  uint64_t messages = 0;
  // The file's bytes [0, clean_end) can stay as they are: they hold the first `clean_chunks`
  // chunks (the last of which may need its indexes rewritten) and nothing damaged; `in_place`
  // is false when something trusted lies beyond (then only a copy keeps it).
  uint64_t clean_end = 8;
  size_t clean_chunks = 0;
  bool in_place = true;
  bool data_end = false;  // a Data End record whose CRC holds: what follows is the summary
};

// Scans a whole file (mapped). `message_index`: whether chunks get Message Index records.
FileScan scan_mcap(std::span<const uint8_t> file, bool message_index);

}  // namespace modd::archive
