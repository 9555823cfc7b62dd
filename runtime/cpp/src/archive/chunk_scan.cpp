#include "modd/archive/chunk_scan.hpp"

#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <optional>

#include "modd/archive/crc32.hpp"
#include "modd/archive/recover.hpp"

namespace modd::archive {

namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
enum Op : uint8_t {
  kHeader = 0x01,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kDataEnd = 0x0F,
};

template <typename T>
T rd(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

// Bounds-checked little-endian reader over one record body; throws Short on a short read.
struct Cursor {
  const uint8_t* p;
  size_t n, at = 0;
  struct Short {};
  template <typename T>
  T get() {
    if (n - at < sizeof(T)) throw Short{};
    T v = rd<T>(p + at);
    at += sizeof(T);
    return v;
  }
  std::string str() {
    auto b = bytes(get<uint32_t>());
    return {reinterpret_cast<const char*>(b.data()), b.size()};
  }
  std::span<const uint8_t> bytes(uint64_t len) {
    if (n - at < len) throw Short{};
    std::span<const uint8_t> s(p + at, len);
    at += len;
    return s;
  }
  bool done() const { return at == n; }
};

// Whether `in` could decompress to `size` bytes at all, checked before anything is allocated:
// a crafted size (up to the bound) with a few bytes of data costs nothing.
bool plausible(const std::string& comp, std::span<const uint8_t> in, uint64_t size) {
  if (size > kMaxChunkBytes) return false;  // a torn or crafted header
  if (comp.empty()) return in.size() == size;
  if (comp == "zstd") {  // the size in the frame's header (the writer puts it there) must agree
    unsigned long long declared = ZSTD_getFrameContentSize(in.data(), in.size());
    return declared != ZSTD_CONTENTSIZE_ERROR &&
           (declared == ZSTD_CONTENTSIZE_UNKNOWN || declared == size);
  }
  return comp == "lz4" && size <= in.size() * 256ull + 64;  // LZ4's ratio is below 255:1
}

bool decompress(const std::string& comp, std::span<const uint8_t> in, uint64_t size,
                std::vector<uint8_t>& out) {
  if (!plausible(comp, in, size)) return false;
  out.resize(size);
  if (comp.empty()) {
    if (in.size() != size) return false;
    std::memcpy(out.data(), in.data(), size);
    return true;
  }
  if (comp == "zstd") {  // writes at most `size` bytes: a bomb stops there
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

using Schemas = std::map<uint16_t, FileScan::Schema>;
using Channels = std::map<uint16_t, FileScan::Channel>;

// Parses a Schema or Channel body exactly (every byte used); false if it does not.
bool parse_schema(Cursor c, FileSpan at, uint16_t& id, FileScan::Schema& s) {
  id = c.get<uint16_t>();
  s.name = c.str();
  s.encoding = c.str();
  auto data = c.bytes(c.get<uint32_t>());
  s.data.assign(data.begin(), data.end());
  s.at = at;
  return c.done() && id != 0;
}

bool parse_channel(Cursor c, FileSpan at, const Schemas& schemas, uint16_t& id,
                   FileScan::Channel& ch) {
  id = c.get<uint16_t>();
  ch.schema = c.get<uint16_t>();
  ch.topic = c.str();
  ch.encoding = c.str();
  auto mb = c.bytes(c.get<uint32_t>());
  Cursor m{mb.data(), mb.size()};
  while (!m.done()) {
    std::string k = m.str();
    ch.meta[k] = m.str();
  }
  ch.at = at;
  return c.done() && (ch.schema == 0 || schemas.count(ch.schema));
}

// The Message Index records a writer puts after a chunk of these records (one per channel,
// entries in record order), and the messages per channel. False if the records are not well
// formed or use a channel never defined.
bool index_chunk(const std::vector<uint8_t>& recs, Schemas& schemas, Channels& channels,
                 ScannedChunk& out) {
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> entries;
  Schemas s2 = schemas;
  Channels c2 = channels;
  size_t at = 0;
  while (at < recs.size()) {
    if (recs.size() - at < 9) return false;
    uint8_t op = recs[at];
    uint64_t len = rd<uint64_t>(recs.data() + at + 1);
    if (recs.size() - at - 9 < len) return false;
    Cursor c{recs.data() + at + 9, len};
    FileSpan none{};
    uint16_t id = 0;
    if (op == kMessage) {
      uint16_t ch = c.get<uint16_t>();
      c.get<uint32_t>();
      uint64_t t = c.get<uint64_t>();
      if (!c2.count(ch)) return false;
      entries[ch].emplace_back(t, at);
    } else if (op == kSchema) {
      FileScan::Schema s;
      if (!parse_schema(c, none, id, s)) return false;
      s2.emplace(id, std::move(s));
    } else if (op == kChannel) {
      FileScan::Channel ch;
      if (!parse_channel(c, none, s2, id, ch)) return false;
      c2.emplace(id, std::move(ch));
    }
    at += 9 + len;
  }
  for (const auto& [ch, es] : entries) {
    out.counts[ch] = es.size();
    out.index_at[ch] = out.index.size();
    uint64_t len = 2 + 4 + es.size() * 16;
    uint32_t elen = static_cast<uint32_t>(es.size() * 16);
    out.index.push_back(kMessageIndex);
    out.index.insert(out.index.end(), reinterpret_cast<const uint8_t*>(&len),
                     reinterpret_cast<const uint8_t*>(&len) + 8);
    out.index.insert(out.index.end(), reinterpret_cast<const uint8_t*>(&ch),
                     reinterpret_cast<const uint8_t*>(&ch) + 2);
    out.index.insert(out.index.end(), reinterpret_cast<const uint8_t*>(&elen),
                     reinterpret_cast<const uint8_t*>(&elen) + 4);
    for (const auto& [t, off] : es) {
      out.index.insert(out.index.end(), reinterpret_cast<const uint8_t*>(&t),
                       reinterpret_cast<const uint8_t*>(&t) + 8);
      out.index.insert(out.index.end(), reinterpret_cast<const uint8_t*>(&off),
                       reinterpret_cast<const uint8_t*>(&off) + 8);
    }
  }
  schemas = std::move(s2);
  channels = std::move(c2);
  return true;
}

// A chunk header that agrees with its record length (cheap: the resync tries it at every
// byte of a damaged region before decompressing anything).
bool chunk_header_fits(std::span<const uint8_t> f, size_t at) {
  if (f.size() - at < 9 + 40 || f[at] != kChunk) return false;
  uint64_t len = rd<uint64_t>(&f[at + 1]);
  if (len > f.size() - at - 9 || len < 40) return false;
  uint32_t clen_name = rd<uint32_t>(&f[at + 9 + 28]);
  if (clen_name > 4 || 40 + uint64_t{clen_name} > len) return false;
  uint64_t clen = rd<uint64_t>(&f[at + 9 + 32 + clen_name]);
  return rd<uint64_t>(&f[at + 9 + 16]) <= kMaxChunkBytes && clen == len - 40 - clen_name;
}

std::optional<ScannedChunk> read_chunk(std::span<const uint8_t> f, size_t at, FileScan& s,
                                       std::vector<uint8_t>& plain);

// The chunk at `at` checked whole; its schemas and channels added to the scan's.
std::optional<ScannedChunk> check_chunk(std::span<const uint8_t> f, size_t at, FileScan& s,
                                        std::vector<uint8_t>& plain) {
  if (!chunk_header_fits(f, at)) return std::nullopt;
  try {
    return read_chunk(f, at, s, plain);
  } catch (const Cursor::Short&) {
    return std::nullopt;  // a record inside shorter than its fields
  }
}

std::optional<ScannedChunk> read_chunk(std::span<const uint8_t> f, size_t at, FileScan& s,
                                       std::vector<uint8_t>& plain) {
  Cursor c{&f[at + 9], rd<uint64_t>(&f[at + 1])};
  ScannedChunk out;
  out.ci.start = c.get<uint64_t>();
  out.ci.end = c.get<uint64_t>();
  out.ci.uncompressed_size = c.get<uint64_t>();
  uint32_t crc = c.get<uint32_t>();
  out.ci.compression = c.str();
  out.ci.compressed_size = c.get<uint64_t>();
  auto data = c.bytes(out.ci.compressed_size);
  out.ci.offset = at;
  out.ci.length = 9 + c.n;
  if (!decompress(out.ci.compression, data, out.ci.uncompressed_size, plain)) return std::nullopt;
  if (crc != 0 && crc32(0, plain) != crc) return std::nullopt;
  if (!index_chunk(plain, s.schemas, s.channels, out)) return std::nullopt;
  return out;
}

// Whether `data`, which decompressed to `plain`, is what the writer makes of `plain`. A chunk
// that checks can still hold a flip its decoder ignored; readers with a stricter decoder would
// refuse it, and the file with it. One level-1 compression per kept chunk, at recovery only.
bool as_written(const std::string& compression, std::span<const uint8_t> data,
                const std::vector<uint8_t>& plain) {
  Compression c{};
  if (!parse_compression(compression.empty() ? "none" : compression, c)) return false;
  std::vector<uint8_t> again = compress_chunk(c, plain);
  return std::equal(again.begin(), again.end(), data.begin(), data.end());
}

// Whether a Schema or Channel record at `at` parses exactly and is followed by the end of
// the file or a record that can follow it (a resync must not trust a lookalike in noise).
bool definition_at(std::span<const uint8_t> f, size_t at, FileScan& s, bool add) {
  if (f.size() - at < 9 || (f[at] != kSchema && f[at] != kChannel)) return false;
  uint64_t len = rd<uint64_t>(&f[at + 1]);
  if (len > f.size() - at - 9 || len > (1u << 20)) return false;
  size_t next = at + 9 + len;
  if (next != f.size()) {
    uint8_t op = f[next];
    if (op != kSchema && op != kChannel && op != kChunk && op != kMessageIndex && op != kDataEnd)
      return false;
  }
  Cursor c{&f[at + 9], len};
  uint16_t id = 0;
  FileSpan span{at, 9 + len};
  try {
    if (f[at] == kSchema) {
      FileScan::Schema sc;
      if (!parse_schema(c, span, id, sc)) return false;
      if (add) s.schemas.emplace(id, std::move(sc));
    } else {
      FileScan::Channel ch;
      if (!parse_channel(c, span, s.schemas, id, ch)) return false;
      if (add) s.channels.emplace(id, std::move(ch));
    }
  } catch (const Cursor::Short&) { return false; }
  return true;
}

// The next offset from `from` where a record checks whole, or the file's size.
size_t resync(std::span<const uint8_t> f, size_t from, FileScan& s, std::vector<uint8_t>& plain) {
  for (size_t p = from; p + 9 <= f.size(); ++p) {
    uint8_t op = f[p];
    if (op == kChunk && chunk_header_fits(f, p)) {
      FileScan probe;
      probe.schemas = s.schemas;
      probe.channels = s.channels;
      if (check_chunk(f, p, probe, plain)) return p;
    } else if ((op == kSchema || op == kChannel) && definition_at(f, p, s, false)) {
      return p;
    }
  }
  return f.size();
}

// The Message Index records right after a chunk (each well formed), as a span of the file.
FileSpan indexes_after(std::span<const uint8_t> f, size_t at) {
  size_t j = at;
  while (f.size() - j >= 9 + 6 && f[j] == kMessageIndex) {
    uint64_t len = rd<uint64_t>(&f[j + 1]);
    if (len > f.size() - j - 9 || len < 6 || rd<uint32_t>(&f[j + 11]) != len - 6) break;
    j += 9 + len;
  }
  return {at, j - at};
}

}  // namespace

bool decompress_chunk(const std::string& compression, std::span<const uint8_t> in, uint64_t size,
                      std::vector<uint8_t>& out) {
  return decompress(compression, in, size, out);
}

namespace {

struct Walk {
  std::span<const uint8_t> f;
  bool message_index;
  FileScan s;
  std::vector<uint8_t> plain;
  bool prefix_open = true;  // no damage and no rewritten index met yet

  void keep(uint64_t end) {
    if (prefix_open)
      s.clean_end = end;
    else
      s.in_place = false;
  }
  void skip_from(size_t at, const char* why) {
    size_t to = resync(f, at + 1, s, plain);
    s.skipped.push_back({at, to - at, why});
    prefix_open = false;
    pos = to;
  }
  void chunk(ScannedChunk c) {
    size_t end = c.ci.offset + c.ci.length;
    FileSpan idx = indexes_after(f, end);
    bool same =
        idx.length == c.index.size() && std::memcmp(&f[end], c.index.data(), idx.length) == 0;
    c.index_intact = same || (idx.length == 0 && !message_index);
    if (c.index_intact && !same) c.index.clear(), c.index_at.clear();
    s.messages += [&] {
      uint64_t n = 0;
      for (const auto& [ch, k] : c.counts) n += k;
      return n;
    }();
    pos = end + idx.length;
    if (prefix_open && !c.reencode) {
      s.clean_end = c.index_intact ? pos : end;
      ++s.clean_chunks;
      prefix_open = c.index_intact;
    } else {  // a chunk to write anew cannot stay in place either
      prefix_open = false;
      s.in_place = false;
    }
    s.chunks.push_back(std::move(c));
  }
  size_t pos = 8;

  void run();
};

void Walk::run() {
  while (pos < f.size()) {
    const size_t at = pos;
    if (f.size() - at < 9) {
      s.skipped.push_back({at, f.size() - at, "a record cut short"});
      break;
    }
    uint8_t op = f[at];
    uint64_t len = rd<uint64_t>(&f[at + 1]);
    if (len > f.size() - at - 9) {
      skip_from(at, "a record longer than the rest of the file");
      continue;
    }
    const size_t next = at + 9 + len;
    if (op == kChunk) {
      if (auto c = check_chunk(f, at, s, plain)) {
        const ChunkIndex& ci = c->ci;
        c->reencode = !as_written(
            ci.compression,
            f.subspan(ci.offset + ci.length - ci.compressed_size, ci.compressed_size), plain);
        chunk(std::move(*c));
      } else
        skip_from(at, "a chunk whose data does not check (CRC, size or records)");
    } else if (op == kSchema || op == kChannel) {
      bool known = op == kSchema ? s.schemas.count(rd<uint16_t>(&f[at + 9]))
                                 : s.channels.count(rd<uint16_t>(&f[at + 9]));
      if (len < 2 || !definition_at(f, at, s, true)) {
        skip_from(at, op == kSchema ? "a schema record that does not parse"
                                    : "a channel record that does not parse");
        continue;
      }
      if (!known) keep(next);
      pos = next;
    } else if (op == kHeader && at == 8) {
      s.header = {at, 9 + len};
      keep(next);
      pos = next;
    } else if (op == kDataEnd && len >= 4 && rd<uint32_t>(&f[at + 9]) == crc32(0, f.first(at))) {
      s.data_end = true;  // an interrupted close: its summary is written again
      break;
    } else {
      skip_from(at, "an unexpected record");
    }
  }
}

}  // namespace

FileScan scan_mcap(std::span<const uint8_t> file, bool message_index) {
  Walk w{file, message_index, {}, {}};
  // A damaged magic does not stop the scan: the records after it may all be whole.
  w.s.magic = file.size() >= 8 && std::memcmp(file.data(), kMagic, 8) == 0;
  w.s.clean_end = std::min<uint64_t>(8, file.size());
  w.run();
  return w.s;
}

}  // namespace modd::archive
