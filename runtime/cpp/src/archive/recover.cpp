#include "modd/archive/recover.hpp"

#include <fcntl.h>
#include <lz4frame.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <tuple>

#include "modd/archive/crc32.hpp"
#include "modd/util/error.hpp"
#include "modd/util/log.hpp"

namespace modd::archive {

namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
enum Op : uint8_t { kSchema = 0x03, kChannel = 0x04, kMessage = 0x05, kChunk = 0x06, kDataEnd = 0x0F, kFooter = 0x02 };

// Bounds-checked little-endian reader over one record body; throws on a short read.
struct Cursor {
  const uint8_t* p;
  size_t n, at = 0;
  struct Short {};
  template <typename T> T get() {
    if (n - at < sizeof(T)) throw Short{};
    T v;
    std::memcpy(&v, p + at, sizeof(T));
    at += sizeof(T);
    return v;
  }
  std::string str() {
    uint32_t len = get<uint32_t>();
    if (n - at < len) throw Short{};
    std::string s(reinterpret_cast<const char*>(p + at), len);
    at += len;
    return s;
  }
  std::span<const uint8_t> bytes(uint64_t len) {
    if (n - at < len) throw Short{};
    std::span<const uint8_t> s(p + at, len);
    at += len;
    return s;
  }
};

bool decompress(const std::string& comp, std::span<const uint8_t> in, uint64_t size, std::vector<uint8_t>& out) {
  if (size > (1ull << 28)) return false;  // a chunk closes at chunk_bytes (256 KiB): a bigger size is a torn header
  out.resize(size);
  if (comp.empty()) {
    if (in.size() != size) return false;
    std::memcpy(out.data(), in.data(), size);
    return true;
  }
  if (comp == "zstd") {
    size_t r = ZSTD_decompress(out.data(), out.size(), in.data(), in.size());
    return !ZSTD_isError(r) && r == size;
  }
  if (comp == "lz4") {
    LZ4F_dctx* d = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&d, LZ4F_VERSION))) return false;
    size_t dst = out.size(), src = in.size();
    size_t r = LZ4F_decompress(d, out.data(), &dst, in.data(), &src, nullptr);
    LZ4F_freeDecompressionContext(d);
    return !LZ4F_isError(r) && dst == size;
  }
  return false;
}

// What a file cut by a crash holds up to its last complete record: a chunk counts once it
// and the Message Index records written with it (one per channel it holds, in the same
// write) are whole, so that an indexed reader finds every message the summary announces.
struct Scan {
  std::map<uint16_t, std::tuple<std::string, std::string, std::string>> schemas;  // id -> name, encoding, data
  struct Channel {
    uint16_t schema;
    std::string topic, encoding;
    std::map<std::string, std::string> meta;
  };
  std::map<uint16_t, Channel> channels;
  std::vector<std::pair<ChunkIndex, std::map<uint16_t, uint64_t>>> chunks;  // with messages per channel
  uint64_t messages = 0;

  void schema(Cursor c) {
    uint16_t id = c.get<uint16_t>();
    std::string name = c.str(), enc = c.str();
    uint32_t len = c.get<uint32_t>();
    auto data = c.bytes(len);
    schemas.emplace(id, std::tuple{name, enc, std::string(data.begin(), data.end())});
  }
  void channel(Cursor c) {
    uint16_t id = c.get<uint16_t>(), sid = c.get<uint16_t>();
    std::string topic = c.str(), enc = c.str();
    uint32_t mlen = c.get<uint32_t>();
    Cursor m{c.p + c.at, mlen};
    c.bytes(mlen);
    std::map<std::string, std::string> meta;
    while (m.at < m.n) {
      std::string k = m.str();
      meta[k] = m.str();
    }
    if (sid && !schemas.count(sid)) throw std::out_of_range("schema");
    channels.emplace(id, Channel{sid, topic, enc, meta});
  }
  // The records of a chunk, checked completely before any is used; its messages per channel.
  bool chunk(const std::vector<uint8_t>& recs, std::map<uint16_t, uint64_t>& counts) {
    size_t at = 0;
    while (at < recs.size()) {
      if (recs.size() - at < 9) return false;
      uint64_t len;
      std::memcpy(&len, recs.data() + at + 1, 8);
      if (recs.size() - at - 9 < len) return false;
      at += 9 + len;
    }
    at = 0;
    while (at < recs.size()) {
      uint8_t op = recs[at];
      uint64_t len;
      std::memcpy(&len, recs.data() + at + 1, 8);
      Cursor c{recs.data() + at + 9, len};
      if (op == kSchema) schema(c);
      else if (op == kChannel) channel(c);
      else if (op == kMessage) {
        uint16_t ch = c.get<uint16_t>();
        if (!channels.count(ch)) return false;  // a channel never defined
        ++counts[ch];
      }
      at += 9 + len;
    }
    return true;
  }
};

// A read-only view of a whole file (mapped: a 256 MiB file costs no heap).
struct Mapped {
  const uint8_t* p = nullptr;
  size_t n = 0;
  explicit Mapped(const std::string& path) {
    int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw Error(ErrorCode::Io, "cannot read " + path + ": " + std::strerror(errno));
    struct stat st{};
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
};

constexpr uint8_t kMessageIndex = 0x07;

}  // namespace

bool decompress_chunk(const std::string& compression, std::span<const uint8_t> in, uint64_t size,
                      std::vector<uint8_t>& out) {
  return decompress(compression, in, size, out);
}

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
  uint64_t good = 8;
  uint32_t crc = 0;
  Scan scan;
  {
    Mapped file(path);
    const uint8_t* all = file.p;
    const size_t size = file.n;
    if (size < 8 + 9 || std::memcmp(all, kMagic, 8) != 0) {
      std::filesystem::remove(path);
      res.removed = true;
      res.dropped_bytes = size;
      return res;
    }
    // A chunk read whole, waiting for its Message Index records.
    struct Pending {
      ChunkIndex ci;
      std::map<uint16_t, uint64_t> counts;
    };
    std::optional<Pending> pend;
    auto commit = [&](uint64_t end) {
      res.messages += [&] {
        uint64_t n = 0;
        for (const auto& [ch, k] : pend->counts) n += k;
        return n;
      }();
      ++res.chunks;
      scan.chunks.emplace_back(std::move(pend->ci), std::move(pend->counts));
      pend.reset();
      good = end;
    };
    size_t at = 8;
    std::vector<uint8_t> plain;
    while (size - at >= 9) {
      uint8_t op = all[at];
      uint64_t len;
      std::memcpy(&len, all + at + 1, 8);
      if (size - at - 9 < len) break;  // cut short
      Cursor c{all + at + 9, len};
      const uint64_t next = at + 9 + len;
      if (pend) {
        if (op == kMessageIndex && len >= 2) {
          uint16_t ch = c.get<uint16_t>();
          pend->ci.index_offsets[ch] = at;
          pend->ci.index_length += 9 + len;
          at = next;
          bool all_indexed = true;
          for (const auto& [k, n] : pend->counts) all_indexed &= pend->ci.index_offsets.count(k) > 0;
          if (all_indexed) commit(at);
          continue;
        }
        if (!pend->ci.index_offsets.empty()) break;  // some of its indexes, then something else
        commit(at);                                  // a file written without message indexes
      }
      bool ok = true;
      try {
        if (op == kChunk) {
          ChunkIndex ci;
          ci.start = c.get<uint64_t>();
          ci.end = c.get<uint64_t>();
          uint64_t usize = c.get<uint64_t>();
          uint32_t chunk_crc = c.get<uint32_t>();
          ci.compression = c.str();
          uint64_t clen = c.get<uint64_t>();
          auto data = c.bytes(clen);
          ci.offset = at;
          ci.length = 9 + len;
          ci.compressed_size = clen;
          ci.uncompressed_size = usize;
          std::map<uint16_t, uint64_t> counts;
          ok = decompress(ci.compression, data, usize, plain) && (chunk_crc == 0 || crc32(0, plain) == chunk_crc) &&
               scan.chunk(plain, counts);
          if (ok) {
            pend = Pending{std::move(ci), std::move(counts)};
            at = next;
            if (pend->counts.empty()) commit(at);
            continue;
          }
        } else if (op == kSchema) {
          scan.schema(c);
        } else if (op == kChannel) {
          scan.channel(c);
        } else if (op == kMessage) {
          ok = false;  // messages outside chunks: not written by the PubBroker; the tail is dropped
        } else if (op == kDataEnd || op == kFooter) {
          break;  // an interrupted finish: written again
        }
      } catch (const Cursor::Short&) {
        ok = false;
      } catch (const std::out_of_range&) {
        ok = false;  // a channel or schema id never defined
      }
      if (!ok) break;
      at = next;
      good = at;
    }
    // A last chunk whose indexes never made it: dropped (its samples were never counted
    // archived: the writer counts a chunk once the chunk and its indexes are written).
    if (pend && pend->ci.index_offsets.empty() && !options.message_index) commit(pend->ci.offset + pend->ci.length);
    res.dropped_bytes = size - good;
    crc = crc32(0, std::span(all, good));
  }
  // Finished in place: cut to the last complete record, then Data End, summary and footer
  // appended (a few KiB, so recovery works on a nearly full disk). A crash or a full disk
  // meanwhile leaves a file the next attempt scans to the same point.
  McapWriter w(path, options, McapWriter::Resume{good, crc});
  for (const auto& [id, sch] : scan.schemas) w.adopt_schema(id, std::get<0>(sch), std::get<1>(sch), std::get<2>(sch));
  for (const auto& [id, ch] : scan.channels) w.adopt_channel(id, ch.schema, ch.topic, ch.encoding, ch.meta);
  for (const auto& [ci, counts] : scan.chunks) w.adopt_chunk(ci, counts);
  w.close();
  return res;
}

std::vector<Recovered> recover_dir(const std::string& dir, const std::string& prefix, const WriterOptions& options) {
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
      if (r.removed)
        log_line("archive: removed %s: an empty file left by a crash", name.c_str());
      else
        log_line("archive: recovered %s left open by a crash: %llu messages in %llu chunks kept, %llu torn bytes "
                 "dropped", name.c_str(), static_cast<unsigned long long>(r.messages),
                 static_cast<unsigned long long>(r.chunks), static_cast<unsigned long long>(r.dropped_bytes));
      out.push_back(std::move(r));
    } catch (const Error& err) {
      log_line("archive: cannot recover %s yet: %s (tried again while the broker runs)", name.c_str(), err.what());
      Recovered r;
      r.path = e.path().string();
      r.failed = true;
      out.push_back(std::move(r));
    }
  }
  return out;
}

}  // namespace modd::archive
