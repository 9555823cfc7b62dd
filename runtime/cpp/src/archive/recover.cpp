#include "modd/archive/recover.hpp"

#include <lz4frame.h>
#include <unistd.h>
#include <zstd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

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
  if (size > (1ull << 31)) return false;
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

struct Rebuild {
  McapWriter& w;
  std::map<uint16_t, std::tuple<std::string, std::string, std::string>> schemas;  // id -> name, encoding, data
  std::map<uint16_t, uint16_t> schema_map, channel_map;                            // old id -> new id
  uint64_t messages = 0;

  void schema(Cursor c) {
    uint16_t id = c.get<uint16_t>();
    std::string name = c.str(), enc = c.str();
    uint32_t len = c.get<uint32_t>();
    auto data = c.bytes(len);
    schemas[id] = {name, enc, std::string(data.begin(), data.end())};
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
    if (channel_map.count(id)) return;
    uint16_t new_sid = 0;
    if (sid) {
      auto s = schema_map.find(sid);
      if (s == schema_map.end()) {
        auto& [name, senc, data] = schemas.at(sid);
        s = schema_map.emplace(sid, w.add_schema(name, senc, data)).first;
      }
      new_sid = s->second;
    }
    channel_map[id] = w.add_channel(new_sid, topic, enc, meta);
  }
  void message(Cursor c) {
    uint16_t ch = c.get<uint16_t>();
    uint32_t seq = c.get<uint32_t>();
    uint64_t log_time = c.get<uint64_t>(), pub_time = c.get<uint64_t>();
    auto data = c.bytes(c.n - c.at);
    w.add_message(channel_map.at(ch), seq, log_time, pub_time, data);
    ++messages;
  }
  // The records of a chunk, checked completely before any is used.
  bool chunk(const std::vector<uint8_t>& recs) {
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
      else if (op == kMessage) message(c);
      at += 9 + len;
    }
    return true;
  }
};

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
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(ErrorCode::Io, "cannot read " + path);
  std::vector<uint8_t> all((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (all.size() < 8 + 9 || std::memcmp(all.data(), kMagic, 8) != 0) {
    std::filesystem::remove(path);
    res.removed = true;
    res.dropped_bytes = all.size();
    return res;
  }
  std::string tmp = path + ".recovering";
  uint64_t good = 8;
  try {
    McapWriter w(tmp, options);
    Rebuild rb{w};
    size_t at = 8;
    std::vector<uint8_t> plain;
    while (all.size() - at >= 9) {
      uint8_t op = all[at];
      uint64_t len;
      std::memcpy(&len, all.data() + at + 1, 8);
      if (all.size() - at - 9 < len) break;  // cut short
      Cursor c{all.data() + at + 9, len};
      bool ok = true;
      try {
        if (op == kChunk) {
          c.get<uint64_t>();
          c.get<uint64_t>();
          uint64_t usize = c.get<uint64_t>();
          uint32_t crc = c.get<uint32_t>();
          std::string comp = c.str();
          uint64_t clen = c.get<uint64_t>();
          auto data = c.bytes(clen);
          ok = decompress(comp, data, usize, plain) && (crc == 0 || crc32(0, plain) == crc) && rb.chunk(plain);
          if (ok) ++res.chunks;
        } else if (op == kSchema) {
          rb.schema(c);
        } else if (op == kChannel) {
          rb.channel(c);
        } else if (op == kMessage) {
          rb.message(c);
        } else if (op == kDataEnd || op == kFooter) {
          break;
        }
      } catch (const Cursor::Short&) {
        ok = false;
      } catch (const std::out_of_range&) {
        ok = false;  // a channel or schema id never defined
      }
      if (!ok) break;
      at += 9 + len;
      good = at;
    }
    res.messages = rb.messages;
    w.close();
  } catch (...) {
    // No room (or no write) for the rebuilt copy: the original stays as it was, and the
    // partial copy must not keep the space the archive needs for new samples.
    std::error_code rm;
    std::filesystem::remove(tmp, rm);
    throw;
  }
  res.dropped_bytes = all.size() - good;
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw Error(ErrorCode::Io, "cannot replace " + path + ": " + ec.message());
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
      log_line("archive: cannot recover %s: %s", name.c_str(), err.what());
    }
  }
  return out;
}

}  // namespace modd::archive
