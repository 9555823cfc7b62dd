// A small MCAP writer following the published specification
// (https://mcap.dev/spec): magic, header, schemas and channels, compressed
// chunks with CRCs, message indexes, data end with the data-section CRC, a
// summary (schemas, channels, statistics, chunk indexes), summary offsets and
// the footer with the summary CRC. Not thread-safe: one writer thread owns it.
#pragma once
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

namespace modd::archive {

enum class Compression { None, Zstd, Lz4 };
// Chunk: the archiver fsyncs the written chunks at every flush tick (so at most once per
// flush interval, not once per chunk at high rates) and at close; Close: at close only.
enum class FsyncPolicy { Never, Chunk, Close };

bool parse_compression(const std::string& s, Compression& out);
bool parse_fsync(const std::string& s, FsyncPolicy& out);
// A chunk's records compressed as the writer compresses them (zstd level 1, an LZ4 frame with
// its content size, or as they are). Throws Error(Internal) if the codec fails.
std::vector<uint8_t> compress_chunk(Compression c, const std::vector<uint8_t>& in);

struct WriterOptions {
  Compression compression = Compression::Zstd;
  size_t chunk_bytes = 256 * 1024;  // uncompressed chunk size that closes a chunk
  FsyncPolicy fsync = FsyncPolicy::Chunk;
  // MCAP Message Index records (16 B per message, never compressed). On by default:
  // the indexed readers Foxglove and Lichtblick open files with (@mcap/core's
  // McapIndexedReader) refuse chunk indexes without them. Off halves the bytes
  // written per sample, for archives read only front to back.
  bool message_index = true;
  std::string library = "modd-pubbroker";
};

// A chunk as the summary's Chunk Index describes it.
struct ChunkIndex {
  uint64_t start = 0, end = 0, offset = 0, length = 0;  // log times; the Chunk record's place
  std::map<uint16_t, uint64_t> index_offsets;           // channel -> its Message Index record
  uint64_t index_length = 0, compressed_size = 0, uncompressed_size = 0;
  std::string compression;
};

class McapWriter {
 public:
  // Creates (truncates) path and writes magic + header. Throws Error(Io).
  McapWriter(const std::string& path, WriterOptions options);
  // Reopens a file a crash left unfinished, to finish it in place (archive recovery, which
  // then needs no room for a copy): the file is cut to `offset`, the end of its last complete
  // record, whose data-section CRC so far is `data_crc`; the caller adopts the schemas,
  // channels and chunks before it, and close() appends Data End, summary and footer.
  struct Resume {
    uint64_t offset;
    uint32_t data_crc;
  };
  McapWriter(const std::string& path, WriterOptions options, Resume at);
  void adopt_schema(uint16_t id, const std::string& name, const std::string& encoding,
                    const std::string& data);
  void adopt_channel(uint16_t id, uint16_t schema_id, const std::string& topic,
                     const std::string& encoding,
                     const std::map<std::string, std::string>& metadata);
  // A chunk already in the file, with its messages per channel.
  void adopt_chunk(const ChunkIndex& chunk, const std::map<uint16_t, uint64_t>& channel_counts);
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  uint16_t add_schema(const std::string& name, const std::string& encoding,
                      const std::string& data);
  uint16_t add_channel(uint16_t schema_id, const std::string& topic,
                       const std::string& message_encoding,
                       const std::map<std::string, std::string>& metadata = {});
  void add_message(uint16_t channel_id, uint32_t sequence, uint64_t log_time, uint64_t publish_time,
                   std::span<const uint8_t> data);
  // The same without closing a full chunk: the caller calls flush_chunk() when chunk_full().
  void append_message(uint16_t channel_id, uint32_t sequence, uint64_t log_time,
                      uint64_t publish_time, std::span<const uint8_t> data);
  bool chunk_full() const { return chunk_.size() >= opt_.chunk_bytes; }
  // Writes the open chunk (if any) and its message indexes. On a write error (Error(Io),
  // e.g. disk full) nothing is lost: what was not written stays pending, and a later
  // flush_chunk() or close() writes it from where the file ends.
  void flush_chunk();
  void sync();     // fsync of what was written
  void close();    // flush, summary, footer, magic; idempotent; resumable after a write error
  void abandon();  // closes the descriptor as the file is (left for recovery at next start)
  uint64_t file_bytes() const { return offset_ + pending_.size(); }
  // Chunks written to this file (their indexes are held for the summary).
  size_t chunk_count() const { return chunk_indexes_.size(); }
  uint64_t message_count() const { return message_count_; }
  uint64_t flushed_messages() const { return flushed_messages_; }  // in chunks written to the file
  uint64_t pending_bytes() const { return pending_.size(); }
  bool closing() const { return closed_ && fd_ >= 0; }  // a close() to resume
  const std::string& path() const { return path_; }

 private:
  struct SchemaRec {
    uint16_t id;
    std::string name, encoding, data;
  };
  struct ChannelRec {
    uint16_t id, schema_id;
    std::string topic, encoding;
    std::map<std::string, std::string> metadata;
  };
  using ChunkIndexRec = ChunkIndex;
  void emit(std::span<const uint8_t> b);  // appends to the file, updating offset and CRC
  void write_out();                       // pending_ -> fd
  void finish_close();
  std::vector<uint8_t> schema_record(const SchemaRec& s) const;
  std::vector<uint8_t> channel_record(const ChannelRec& c) const;

  std::string path_;
  WriterOptions opt_;
  int fd_ = -1;
  bool closed_ = false;
  uint64_t offset_ = 0;           // bytes already written to fd
  std::vector<uint8_t> pending_;  // emitted but not yet written
  uint32_t data_crc_ = 0;
  std::vector<SchemaRec> schemas_;
  std::vector<ChannelRec> channels_;
  std::vector<ChunkIndexRec> chunk_indexes_;
  std::map<uint16_t, uint64_t> channel_counts_;
  uint64_t flushed_messages_ = 0, staged_messages_ = 0;
  uint64_t message_count_ = 0, first_time_ = UINT64_MAX, last_time_ = 0;
  // open chunk
  std::vector<uint8_t> chunk_;
  uint64_t chunk_start_ = UINT64_MAX, chunk_end_ = 0;
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_index_;
};

}  // namespace modd::archive
