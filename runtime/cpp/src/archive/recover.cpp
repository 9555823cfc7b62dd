#include "modd/archive/recover.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "modd/archive/crc32.hpp"
#include "modd/util/error.hpp"
#include "modd/util/log.hpp"

namespace modd::archive {

namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};

// A read-only view of a whole file (mapped: a 256 MiB file costs no heap).
struct Mapped {
  const uint8_t* p = nullptr;
  size_t n = 0;
  explicit Mapped(const std::string& path) {
    int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw Error(ErrorCode::Io, "cannot read " + path + ": " + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) == 0 && st.st_size > 0) {
      void* m = ::mmap(nullptr, static_cast<size_t>(st.st_size), PROT_READ, MAP_PRIVATE, fd, 0);
      if (m != MAP_FAILED) {
        p = static_cast<const uint8_t*>(m);
        n = static_cast<size_t>(st.st_size);
      }
    }
    ::close(fd);
    if (st.st_size > 0 && !p) throw Error(ErrorCode::Io, "cannot map " + path);
  }
  ~Mapped() {
    if (p) ::munmap(const_cast<uint8_t*>(p), n);
  }
  Mapped(const Mapped&) = delete;
  Mapped& operator=(const Mapped&) = delete;
  std::span<const uint8_t> all() const { return {p, n}; }
};

// Hands the scan's schemas, channels and chunks to a writer that finishes a file; `placed[i]`
// is chunk i as the finished file holds it (offset, length, compressed size), its indexes
// right after it.
void adopt(McapWriter& w, const FileScan& s, const std::vector<ChunkIndex>& placed) {
  for (const auto& [id, sc] : s.schemas) w.adopt_schema(id, sc.name, sc.encoding, sc.data);
  for (const auto& [id, ch] : s.channels)
    w.adopt_channel(id, ch.schema, ch.topic, ch.encoding, ch.meta);
  for (size_t i = 0; i < placed.size(); ++i) {
    const ScannedChunk& c = s.chunks[i];
    ChunkIndex ci = placed[i];
    ci.index_offsets.clear();
    for (const auto& [ch, off] : c.index_at) ci.index_offsets[ch] = ci.offset + ci.length + off;
    ci.index_length = c.index.size();
    w.adopt_chunk(ci, c.counts);
  }
}

// The Chunk record of `c` written anew from its data: its times, size, CRC and compression as
// they were, its records compressed as the writer compresses them; `ci` gets the new sizes.
std::vector<uint8_t> chunk_anew(std::span<const uint8_t> file, const ScannedChunk& c,
                                ChunkIndex& ci) {
  const uint64_t fields = 8 + 8 + 8 + 4 + 4 + c.ci.compression.size();  // up to compressed size
  std::vector<uint8_t> plain;
  Compression comp{};
  if (!decompress_chunk(
          c.ci.compression,
          file.subspan(c.ci.offset + c.ci.length - c.ci.compressed_size, c.ci.compressed_size),
          c.ci.uncompressed_size, plain) ||
      !parse_compression(c.ci.compression.empty() ? "none" : c.ci.compression, comp))
    throw Error(ErrorCode::Internal, "a kept chunk no longer decompresses");
  std::vector<uint8_t> data = compress_chunk(comp, plain);
  const uint64_t csize = data.size();
  const uint64_t body = fields + 8 + csize;
  auto head = file.subspan(c.ci.offset + 9, fields);
  std::vector<uint8_t> rec(9 + body);
  rec[0] = file[c.ci.offset];
  std::memcpy(&rec[1], &body, 8);
  std::memcpy(&rec[9], head.data(), fields);
  std::memcpy(&rec[9 + fields], &csize, 8);
  if (csize) std::memcpy(&rec[9 + fields + 8], data.data(), csize);
  ci.length = rec.size();
  ci.compressed_size = csize;
  return rec;
}

// Appends bytes to a descriptor, keeping the data-section CRC; throws Error(Io).
struct Out {
  int fd;
  const std::string& path;
  uint64_t at = 0;
  uint32_t crc = 0;
  void put(std::span<const uint8_t> b) {
    crc = crc32(crc, b);
    for (size_t done = 0; done < b.size();) {
      ssize_t n = ::write(fd, b.data() + done, b.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw Error(ErrorCode::Io, "write " + path + ": " + std::strerror(errno));
      done += static_cast<size_t>(n);
    }
    at += b.size();
  }
};

void sync_path(const std::string& path) {
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

// Finished in place: nothing trusted lies past `clean_end` (what is cut holds no whole chunk),
// so the file is cut there, the last kept chunk's indexes rewritten if they were torn, then
// Data End, summary and footer appended: room for a few KiB is enough.
void finish_in_place(const std::string& path, const FileScan& s, std::span<const uint8_t> file,
                     const WriterOptions& options) {
  std::vector<uint8_t> tail;
  if (s.clean_chunks && !s.chunks[s.clean_chunks - 1].index_intact)
    tail = s.chunks[s.clean_chunks - 1].index;
  uint32_t crc = crc32(crc32(0, file.first(s.clean_end)), tail);
  {
    int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) throw Error(ErrorCode::Io, "cannot open " + path + ": " + std::strerror(errno));
    Out out{fd, path, s.clean_end};
    int err = ::lseek(fd, static_cast<off_t>(s.clean_end), SEEK_SET) < 0 ? errno : 0;
    try {
      if (!err) out.put(tail);
    } catch (...) {
      ::close(fd);
      throw;
    }
    ::close(fd);
    if (err) throw Error(ErrorCode::Io, "cannot seek " + path + ": " + std::strerror(err));
  }
  McapWriter w(path, options, McapWriter::Resume{s.clean_end + tail.size(), crc});
  std::vector<ChunkIndex> placed;
  for (size_t i = 0; i < s.clean_chunks; ++i) placed.push_back(s.chunks[i].ci);
  adopt(w, s, placed);
  w.close();
}

// Writes the trusted records beside the original (`.recovering`): magic, header, schemas,
// channels, then each kept chunk with its Message Index records (as it was, or written anew
// from its data when its bytes were not the writer's), then the summary.
void write_copy(const std::string& tmp, const FileScan& s, std::span<const uint8_t> file,
                const WriterOptions& options) {
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw Error(ErrorCode::Io, "cannot create " + tmp + ": " + std::strerror(errno));
  Out out{fd, tmp};
  std::vector<ChunkIndex> placed;
  try {
    out.put(kMagic);
    if (s.header.length) {
      out.put(file.subspan(s.header.offset, s.header.length));
    } else {  // opcode, length 8, two empty strings (profile, library)
      const uint8_t h[17] = {0x01, 8};
      out.put(h);
    }
    for (const auto& [id, sc] : s.schemas)
      if (sc.at.length) out.put(file.subspan(sc.at.offset, sc.at.length));
    for (const auto& [id, ch] : s.channels)
      if (ch.at.length) out.put(file.subspan(ch.at.offset, ch.at.length));
    for (const ScannedChunk& c : s.chunks) {
      ChunkIndex ci = c.ci;
      ci.offset = out.at;
      if (c.reencode)
        out.put(chunk_anew(file, c, ci));
      else
        out.put(file.subspan(c.ci.offset, c.ci.length));
      out.put(c.index);
      placed.push_back(std::move(ci));
    }
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  WriterOptions o = options;
  o.fsync = FsyncPolicy::Close;
  McapWriter w(tmp, o, McapWriter::Resume{out.at, out.crc});
  adopt(w, s, placed);
  w.close();
}

// The copy read back: every chunk whole, the same messages, closed.
void verify_copy(const std::string& tmp, const FileScan& s, bool message_index) {
  Mapped m(tmp);
  FileScan v = scan_mcap(m.all(), message_index);
  bool as_written = std::none_of(v.chunks.begin(), v.chunks.end(),
                                 [](const ScannedChunk& c) { return c.reencode; });
  if (!v.magic || !v.skipped.empty() || !v.data_end || v.chunks.size() != s.chunks.size() ||
      v.messages != s.messages || !as_written || !mcap_complete(tmp))
    throw Error(ErrorCode::Internal, "the recovered copy " + tmp + " does not read back whole");
}

}  // namespace

bool mcap_complete(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return false;
  f.seekg(0, std::ios::end);
  auto size = static_cast<int64_t>(f.tellg());
  if (size < 16) return false;
  f.seekg(size - 8);
  uint8_t tail[8];
  f.read(reinterpret_cast<char*>(tail), 8);
  return f && std::memcmp(tail, kMagic, 8) == 0;
}

Recovered recover_mcap(const std::string& path, const WriterOptions& options) {
  Recovered res;
  res.path = path;
  Mapped file(path);
  if (file.n < 8 + 9) {  // nothing but a partial magic or header
    std::filesystem::remove(path);
    res.removed = true;
    res.dropped_bytes = file.n;
    return res;
  }
  FileScan s = scan_mcap(file.all(), options.message_index);
  res.skipped = s.skipped;
  res.messages = s.messages;
  res.chunks = s.chunks.size();
  res.rewritten_chunks = static_cast<uint64_t>(std::count_if(
      s.chunks.begin(), s.chunks.end(), [](const ScannedChunk& c) { return c.reencode; }));
  if (!s.magic && s.chunks.empty() && s.channels.empty()) {
    res.foreign = true;  // not an MCAP file: left as it is
    return res;
  }
  if (s.magic && s.in_place) {
    res.dropped_bytes = file.n - s.clean_end;
    finish_in_place(path, s, file.all(), options);
    return res;
  }
  // Something trusted lies past a damaged region: a copy keeps it, and replaces the original
  // only once it reads back whole. Without room for it, the original stays as it is.
  const std::string tmp = path + ".recovering";
  try {
    write_copy(tmp, s, file.all(), options);
    verify_copy(tmp, s, options.message_index);
    sync_path(tmp);
    if (::rename(tmp.c_str(), path.c_str()) != 0)
      throw Error(ErrorCode::Io, "cannot replace " + path + ": " + std::strerror(errno));
    sync_path(std::filesystem::path(path).parent_path().string());
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
  res.rewritten = true;
  for (const Skipped& k : s.skipped) res.dropped_bytes += k.length;
  return res;
}

void log_recovered(const std::string& name, const Recovered& r, const char* when) {
  auto u = [](uint64_t v) { return static_cast<unsigned long long>(v); };
  if (r.removed) {
    log_line("archive: removed %s: an empty file left by a crash", name.c_str());
    return;
  }
  if (r.foreign) {
    log_line("archive: %s is not an MCAP file (no magic, no record found): left as it is",
             name.c_str());
    return;
  }
  log_line(
      "archive: recovered %s left open by a crash%s%s: %llu messages in %llu chunks kept, %llu "
      "damaged or "
      "torn bytes dropped in %zu regions",
      name.c_str(), when,
      r.rewritten ? " (written beside it, read back, then renamed over it)" : "", u(r.messages),
      u(r.chunks), u(r.dropped_bytes), r.skipped.size());
  if (r.rewritten_chunks)
    log_line(
        "archive:   %llu chunks written anew from their data (their bytes were not the "
        "writer's: a damaged byte their decoder read past, or another writer)",
        u(r.rewritten_chunks));
  for (size_t i = 0; i < r.skipped.size() && i < 20; ++i)
    log_line("archive:   skipped %llu bytes at offset %llu: %s", u(r.skipped[i].length),
             u(r.skipped[i].offset), r.skipped[i].why.c_str());
}

std::vector<Recovered> recover_dir(const std::string& dir, const std::string& prefix,
                                   const WriterOptions& options) {
  std::vector<Recovered> out;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    if (!e.is_regular_file()) continue;
    std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    if (name.ends_with(".mcap.recovering")) {
      std::filesystem::remove(e.path(), ec);  // an interrupted recovery: the original is intact
      continue;
    }
    if (!name.ends_with(".mcap") || mcap_complete(e.path().string())) continue;
    try {
      Recovered r = recover_mcap(e.path().string(), options);
      log_recovered(name, r);
      out.push_back(std::move(r));
    } catch (const Error& err) {
      log_line("archive: cannot recover %s yet: %s (tried again while the broker runs)",
               name.c_str(), err.what());
      Recovered r;
      r.path = e.path().string();
      r.failed = true;
      out.push_back(std::move(r));
    }
  }
  return out;
}

}  // namespace modd::archive
