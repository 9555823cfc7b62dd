#include "modd/archive/mcap_writer.hpp"

#include <fcntl.h>
#include <lz4frame.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <memory>

#include "modd/archive/crc32.hpp"
#include "modd/util/error.hpp"

namespace modd::archive {

namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
enum Op : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// Little-endian record builder.
struct Rec {
  std::vector<uint8_t> b;
  explicit Rec(uint8_t op) {
    b.push_back(op);
    b.resize(9);
  }  // opcode + u64 length placeholder
  template <typename T>
  void put(T v) {
    uint8_t x[sizeof(T)];
    std::memcpy(x, &v, sizeof(T));
    b.insert(b.end(), x, x + sizeof(T));
  }
  void str(const std::string& s) {
    put<uint32_t>(static_cast<uint32_t>(s.size()));
    b.insert(b.end(), s.begin(), s.end());
  }
  void raw(std::span<const uint8_t> d) { b.insert(b.end(), d.begin(), d.end()); }
  std::vector<uint8_t>&& done() {
    uint64_t len = b.size() - 9;
    std::memcpy(b.data() + 1, &len, 8);
    return std::move(b);
  }
};

const char* compression_name(Compression c) {
  return c == Compression::Zstd ? "zstd" : c == Compression::Lz4 ? "lz4" : "";
}

}  // namespace

bool parse_compression(const std::string& s, Compression& out) {
  if (s == "zstd")
    out = Compression::Zstd;
  else if (s == "lz4")
    out = Compression::Lz4;
  else if (s == "none")
    out = Compression::None;
  else
    return false;
  return true;
}

bool parse_fsync(const std::string& s, FsyncPolicy& out) {
  if (s == "never")
    out = FsyncPolicy::Never;
  else if (s == "chunk")
    out = FsyncPolicy::Chunk;
  else if (s == "close")
    out = FsyncPolicy::Close;
  else
    return false;
  return true;
}

std::vector<uint8_t> compress_chunk(Compression c, const std::vector<uint8_t>& in) {
  std::vector<uint8_t> out;
  if (c == Compression::Zstd) {
    // One context per thread, reused: a fresh one per chunk costs its allocation and setup.
    thread_local std::unique_ptr<ZSTD_CCtx, size_t (*)(ZSTD_CCtx*)> cctx{ZSTD_createCCtx(),
                                                                         ZSTD_freeCCtx};
    if (!cctx) throw Error(ErrorCode::Internal, "zstd: cannot create a compression context");
    out.resize(ZSTD_compressBound(in.size()));
    size_t n = ZSTD_compressCCtx(cctx.get(), out.data(), out.size(), in.data(), in.size(), 1);
    if (ZSTD_isError(n))
      throw Error(ErrorCode::Internal, std::string("zstd: ") + ZSTD_getErrorName(n));
    out.resize(n);
  } else if (c == Compression::Lz4) {
    LZ4F_preferences_t prefs{};
    prefs.frameInfo.contentSize = in.size();
    out.resize(LZ4F_compressFrameBound(in.size(), &prefs));
    size_t n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), &prefs);
    if (LZ4F_isError(n))
      throw Error(ErrorCode::Internal, std::string("lz4: ") + LZ4F_getErrorName(n));
    out.resize(n);
  } else {
    out = in;
  }
  return out;
}

McapWriter::McapWriter(const std::string& path, WriterOptions options)
    : path_(path), opt_(std::move(options)) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw Error(ErrorCode::Io, "cannot create " + path + ": " + std::strerror(errno));
  emit(kMagic);
  Rec h(kHeader);
  h.str("");  // profile: none (JSON messages need no ROS profile)
  h.str(opt_.library);
  emit(h.done());
  // Written with the first chunk: opening a file writes nothing, so a full disk never
  // leaves a trail of empty files.
}

McapWriter::McapWriter(const std::string& path, WriterOptions options, Resume at)
    : path_(path), opt_(std::move(options)) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd_ < 0) throw Error(ErrorCode::Io, "cannot open " + path + ": " + std::strerror(errno));
  if (::ftruncate(fd_, static_cast<off_t>(at.offset)) != 0 ||
      ::lseek(fd_, static_cast<off_t>(at.offset), SEEK_SET) < 0) {
    int err = errno;
    ::close(fd_);
    fd_ = -1;
    throw Error(ErrorCode::Io, "cannot cut " + path + ": " + std::strerror(err));
  }
  offset_ = at.offset;
  data_crc_ = at.data_crc;
}

void McapWriter::adopt_schema(uint16_t id, const std::string& name, const std::string& encoding,
                              const std::string& data) {
  schemas_.push_back({id, name, encoding, data});
}

void McapWriter::adopt_channel(uint16_t id, uint16_t schema_id, const std::string& topic,
                               const std::string& encoding,
                               const std::map<std::string, std::string>& metadata) {
  channels_.push_back({id, schema_id, topic, encoding, metadata});
}

void McapWriter::adopt_chunk(const ChunkIndex& chunk,
                             const std::map<uint16_t, uint64_t>& channel_counts) {
  uint64_t n = 0;
  for (const auto& [ch, k] : channel_counts) {
    channel_counts_[ch] += k;
    n += k;
  }
  if (n) {
    first_time_ = std::min(first_time_, chunk.start);
    last_time_ = std::max(last_time_, chunk.end);
  }
  message_count_ += n;
  staged_messages_ = flushed_messages_ = message_count_;
  chunk_indexes_.push_back(chunk);
}

McapWriter::~McapWriter() {
  try {
    close();
  } catch (...) {}
  if (fd_ >= 0) ::close(fd_);
}

void McapWriter::emit(std::span<const uint8_t> b) {
  if (!closed_) data_crc_ = crc32(data_crc_, b);  // the data section ends at Data End
  pending_.insert(pending_.end(), b.begin(), b.end());
}

void McapWriter::write_out() {
  // On a write error (disk full) the bytes written so far stay counted in offset_ and the
  // rest stays pending: calling again resumes exactly where the file ends.
  size_t done = 0;
  auto keep_rest = [&] {
    offset_ += done;
    pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(done));
  };
  while (done < pending_.size()) {
    ssize_t n = ::write(fd_, pending_.data() + done, pending_.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      int err = errno;
      keep_rest();
      throw Error(ErrorCode::Io, "write " + path_ + ": " + std::strerror(err));
    }
    done += static_cast<size_t>(n);
  }
  offset_ += pending_.size();
  pending_.clear();
  flushed_messages_ = staged_messages_;
}

std::vector<uint8_t> McapWriter::schema_record(const SchemaRec& s) const {
  Rec r(kSchema);
  r.put<uint16_t>(s.id);
  r.str(s.name);
  r.str(s.encoding);
  r.put<uint32_t>(static_cast<uint32_t>(s.data.size()));
  r.raw(std::span(reinterpret_cast<const uint8_t*>(s.data.data()), s.data.size()));
  return r.done();
}

std::vector<uint8_t> McapWriter::channel_record(const ChannelRec& c) const {
  Rec r(kChannel);
  r.put<uint16_t>(c.id);
  r.put<uint16_t>(c.schema_id);
  r.str(c.topic);
  r.str(c.encoding);
  uint32_t mlen = 0;
  for (const auto& [k, v] : c.metadata) mlen += static_cast<uint32_t>(8 + k.size() + v.size());
  r.put<uint32_t>(mlen);
  for (const auto& [k, v] : c.metadata) {
    r.str(k);
    r.str(v);
  }
  return r.done();
}

uint16_t McapWriter::add_schema(const std::string& name, const std::string& encoding,
                                const std::string& data) {
  SchemaRec s{static_cast<uint16_t>(schemas_.size() + 1), name, encoding,
              data};  // id 0 is reserved
  // Outside chunks, so that a reader sees it before any message using it.
  auto rec = schema_record(s);
  emit(rec);
  schemas_.push_back(std::move(s));
  return schemas_.back().id;
}

uint16_t McapWriter::add_channel(uint16_t schema_id, const std::string& topic,
                                 const std::string& enc,
                                 const std::map<std::string, std::string>& metadata) {
  ChannelRec c{static_cast<uint16_t>(channels_.size()), schema_id, topic, enc, metadata};
  emit(channel_record(c));
  channels_.push_back(std::move(c));
  return channels_.back().id;
}

void McapWriter::add_message(uint16_t channel_id, uint32_t sequence, uint64_t log_time,
                             uint64_t publish_time, std::span<const uint8_t> data) {
  append_message(channel_id, sequence, log_time, publish_time, data);
  if (chunk_full()) flush_chunk();
}

void McapWriter::append_message(uint16_t channel_id, uint32_t sequence, uint64_t log_time,
                                uint64_t publish_time, std::span<const uint8_t> data) {
  uint64_t at = chunk_.size();
  uint8_t head[1 + 8 + 2 + 4 + 8 + 8];
  uint64_t len = 2 + 4 + 8 + 8 + data.size();
  head[0] = kMessage;
  std::memcpy(head + 1, &len, 8);
  std::memcpy(head + 9, &channel_id, 2);
  std::memcpy(head + 11, &sequence, 4);
  std::memcpy(head + 15, &log_time, 8);
  std::memcpy(head + 23, &publish_time, 8);
  chunk_.insert(chunk_.end(), head, head + sizeof(head));
  chunk_.insert(chunk_.end(), data.begin(), data.end());
  if (opt_.message_index) chunk_index_[channel_id].emplace_back(log_time, at);
  chunk_start_ = std::min(chunk_start_, log_time);
  chunk_end_ = std::max(chunk_end_, log_time);
  ++message_count_;
  ++channel_counts_[channel_id];
  first_time_ = std::min(first_time_, log_time);
  last_time_ = std::max(last_time_, log_time);
}

void McapWriter::flush_chunk() {
  if (chunk_.empty()) {
    write_out();
    return;
  }
  auto compressed = compress_chunk(opt_.compression, chunk_);
  Rec c(kChunk);
  c.put<uint64_t>(chunk_start_);
  c.put<uint64_t>(chunk_end_);
  c.put<uint64_t>(chunk_.size());
  c.put<uint32_t>(crc32(0, chunk_));
  c.str(compression_name(opt_.compression));
  c.put<uint64_t>(compressed.size());
  c.raw(compressed);
  ChunkIndexRec ci{};
  ci.start = chunk_start_;
  ci.end = chunk_end_;
  ci.offset = file_bytes();
  auto crec = c.done();
  ci.length = crec.size();
  ci.compressed_size = compressed.size();
  ci.uncompressed_size = chunk_.size();
  ci.compression = compression_name(opt_.compression);
  emit(crec);
  uint64_t idx_start = file_bytes();
  for (const auto& [ch, entries] : chunk_index_) {
    Rec m(kMessageIndex);
    m.put<uint16_t>(ch);
    m.put<uint32_t>(static_cast<uint32_t>(entries.size() * 16));
    for (const auto& [t, off] : entries) {
      m.put<uint64_t>(t);
      m.put<uint64_t>(off);
    }
    ci.index_offsets[ch] = file_bytes();
    emit(m.done());
  }
  ci.index_length = file_bytes() - idx_start;
  chunk_indexes_.push_back(std::move(ci));
  staged_messages_ = message_count_;
  chunk_.clear();
  chunk_index_.clear();
  chunk_start_ = UINT64_MAX;
  chunk_end_ = 0;
  write_out();
}

void McapWriter::sync() {
  if (fd_ >= 0) ::fsync(fd_);
}

void McapWriter::close() {
  if (fd_ < 0) return;
  if (closed_) {
    // A close that failed (disk full) resumes: the summary is pending already.
    finish_close();
    return;
  }
  flush_chunk();
  closed_ = true;
  // The data-section CRC covers every byte from the magic to the Data End record.
  Rec de(kDataEnd);
  de.put<uint32_t>(data_crc_);
  emit(de.done());

  uint64_t summary_start = file_bytes();
  std::vector<uint8_t> summary;
  struct Group {
    uint8_t op;
    uint64_t start, length;
  };
  std::vector<Group> groups;
  auto add_group = [&](uint8_t op, const std::vector<std::vector<uint8_t>>& recs) {
    if (recs.empty()) return;
    uint64_t start = summary_start + summary.size();
    for (const auto& r : recs) summary.insert(summary.end(), r.begin(), r.end());
    groups.push_back({op, start, summary_start + summary.size() - start});
  };
  std::vector<std::vector<uint8_t>> recs;
  for (const auto& s : schemas_) recs.push_back(schema_record(s));
  add_group(kSchema, recs);
  recs.clear();
  for (const auto& c : channels_) recs.push_back(channel_record(c));
  add_group(kChannel, recs);
  recs.clear();
  {
    Rec st(kStatistics);
    st.put<uint64_t>(message_count_);
    st.put<uint16_t>(static_cast<uint16_t>(schemas_.size()));
    st.put<uint32_t>(static_cast<uint32_t>(channels_.size()));
    st.put<uint32_t>(0);  // attachments
    st.put<uint32_t>(0);  // metadata
    st.put<uint32_t>(static_cast<uint32_t>(chunk_indexes_.size()));
    st.put<uint64_t>(message_count_ ? first_time_ : 0);
    st.put<uint64_t>(message_count_ ? last_time_ : 0);
    st.put<uint32_t>(static_cast<uint32_t>(channel_counts_.size() * 10));
    for (const auto& [ch, n] : channel_counts_) {
      st.put<uint16_t>(ch);
      st.put<uint64_t>(n);
    }
    recs.push_back(st.done());
  }
  add_group(kStatistics, recs);
  recs.clear();
  for (const auto& ci : chunk_indexes_) {
    Rec r(kChunkIndex);
    r.put<uint64_t>(ci.start);
    r.put<uint64_t>(ci.end);
    r.put<uint64_t>(ci.offset);
    r.put<uint64_t>(ci.length);
    r.put<uint32_t>(static_cast<uint32_t>(ci.index_offsets.size() * 10));
    for (const auto& [ch, off] : ci.index_offsets) {
      r.put<uint16_t>(ch);
      r.put<uint64_t>(off);
    }
    r.put<uint64_t>(ci.index_length);
    r.str(ci.compression);
    r.put<uint64_t>(ci.compressed_size);
    r.put<uint64_t>(ci.uncompressed_size);
    recs.push_back(r.done());
  }
  add_group(kChunkIndex, recs);
  uint64_t summary_offset_start = summary_start + summary.size();
  for (const auto& g : groups) {
    Rec so(kSummaryOffset);
    so.put<uint8_t>(g.op);
    so.put<uint64_t>(g.start);
    so.put<uint64_t>(g.length);
    auto b = so.done();
    summary.insert(summary.end(), b.begin(), b.end());
  }
  Rec f(kFooter);
  f.put<uint64_t>(summary.empty() ? 0 : summary_start);
  f.put<uint64_t>(groups.empty() ? 0 : summary_offset_start);
  std::vector<uint8_t> fb = f.b;  // opcode, length placeholder, two fields
  uint64_t flen = 8 + 8 + 4;
  std::memcpy(fb.data() + 1, &flen, 8);
  std::vector<uint8_t> crc_input = summary;
  crc_input.insert(crc_input.end(), fb.begin(), fb.end());
  uint32_t summary_crc = crc32(0, crc_input);
  emit(summary);
  uint8_t crcb[4];
  std::memcpy(crcb, &summary_crc, 4);
  fb.insert(fb.end(), crcb, crcb + 4);
  emit(fb);
  emit(kMagic);
  finish_close();
}

void McapWriter::finish_close() {
  write_out();
  if (opt_.fsync != FsyncPolicy::Never) ::fsync(fd_);
  ::close(fd_);
  fd_ = -1;
}

void McapWriter::abandon() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

}  // namespace modd::archive
