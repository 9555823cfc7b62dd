// Start-up recovery of crashed MCAP files with damaged bytes (docs/pubbroker.md, "Crash
// bound"): single-byte flips at 25 offsets, each alone and all together. The oracle is this
// file's own minimal reader of the MCAP spec, chunk by chunk over the chunk boundaries of the
// undamaged file (zstd and a bitwise CRC-32 called directly, not the code under test).
#include <gtest/gtest.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <tuple>

#include "modd/archive/mcap_writer.hpp"
#include "modd/archive/recover.hpp"
#include "modd/util/error.hpp"

using namespace modd::archive;

namespace {

using Bytes = std::vector<uint8_t>;

std::string fresh_dir(const std::string& name) {
  auto p = std::filesystem::temp_directory_path() /
           ("modd-recover-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

Bytes slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), {}};
}

void spill(const std::string& path, const Bytes& b) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

template <typename T>
T rd(const Bytes& b, size_t at) {
  T v;
  std::memcpy(&v, b.data() + at, sizeof(T));
  return v;
}

uint32_t bitwise_crc(const Bytes& d) {
  uint32_t c = 0xFFFFFFFFu;
  for (uint8_t byte : d) {
    c ^= byte;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
  }
  return ~c;
}

struct Record {
  uint8_t op;
  size_t at, size;  // whole record, opcode included
};

// The top-level records of an undamaged file, front to back (stops at a torn tail).
std::vector<Record> records(const Bytes& b) {
  std::vector<Record> out;
  size_t at = 8;
  while (b.size() - at >= 9) {
    uint64_t len = rd<uint64_t>(b, at + 1);
    if (len > b.size() - at - 9) break;
    out.push_back({b[at], at, 9 + len});
    at += 9 + len;
  }
  return out;
}

// The messages (channel, log_time, offset) of the chunk record at `at` if its data checks.
std::optional<std::vector<std::tuple<uint16_t, uint64_t, uint64_t>>> chunk_messages(const Bytes& b,
                                                                                    size_t at,
                                                                                    size_t size) {
  if (at + size > b.size() || b[at] != 0x06 || rd<uint64_t>(b, at + 1) != size - 9)
    return std::nullopt;
  uint64_t usize = rd<uint64_t>(b, at + 9 + 16);
  uint32_t crc = rd<uint32_t>(b, at + 9 + 24);
  uint32_t name = rd<uint32_t>(b, at + 9 + 28);
  if (name != 4 || std::memcmp(&b[at + 9 + 32], "zstd", 4) != 0 || usize > (1u << 26))
    return std::nullopt;
  uint64_t clen = rd<uint64_t>(b, at + 9 + 36);
  if (9 + 44 + clen != size) return std::nullopt;
  Bytes plain(usize);
  size_t r = ZSTD_decompress(plain.data(), plain.size(), &b[at + 9 + 44], clen);
  if (ZSTD_isError(r) || r != usize || bitwise_crc(plain) != crc) return std::nullopt;
  std::vector<std::tuple<uint16_t, uint64_t, uint64_t>> msgs;
  for (size_t p = 0; p + 9 <= plain.size();) {
    uint64_t len = rd<uint64_t>(plain, p + 1);
    if (plain[p] == 0x05)
      msgs.emplace_back(rd<uint16_t>(plain, p + 9), rd<uint64_t>(plain, p + 15), p);
    p += 9 + len;
  }
  return msgs;
}

// A crashed file: three channels, many chunks, the last one still open, a torn tail.
Bytes crashed_file(const std::string& dir) {
  std::string path = dir + "/fixture.mcap";
  WriterOptions o;
  o.chunk_bytes = 2048;
  o.fsync = FsyncPolicy::Never;
  McapWriter w(path, o);
  uint16_t s = w.add_schema("modd.float32", "jsonschema", "{}");
  uint16_t ch[3] = {w.add_channel(s, "usv.a", "json"), w.add_channel(s, "usv.b", "json"),
                    w.add_channel(s, "usv.c", "json")};
  for (uint32_t i = 0; i < 3000; ++i) {
    std::string m =
        "{\"value\":" + std::to_string(i * 37 % 1001) + "." + std::to_string(i % 7) + "}";
    w.add_message(ch[i % 3 == 2 ? 2 : i % 2], i, 1000 + i, 900 + i,
                  std::span(reinterpret_cast<const uint8_t*>(m.data()), m.size()));
  }
  w.abandon();
  Bytes b = slurp(path);
  std::filesystem::remove(path);
  b.resize(b.size() - 3);
  return b;
}

// The oracle: messages in the chunks (at the undamaged file's boundaries) whose data checks.
uint64_t oracle_count(const Bytes& damaged, const std::vector<Record>& layout) {
  uint64_t n = 0;
  for (const Record& r : layout)
    if (r.op == 0x06)
      if (auto m = chunk_messages(damaged, r.at, r.size)) n += m->size();
  return n;
}

// Reads a recovered file back: closed, every chunk whole, and every Message Index entry
// pointing at a message of its channel and log time. Returns the messages.
uint64_t read_back(const Bytes& b) {
  static const uint8_t magic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
  EXPECT_EQ(std::memcmp(b.data(), magic, 8), 0);
  EXPECT_EQ(std::memcmp(b.data() + b.size() - 8, magic, 8), 0);
  uint64_t n = 0;
  auto recs = records(b);
  for (size_t i = 0; i < recs.size(); ++i) {
    if (recs[i].op != 0x06) continue;
    auto m = chunk_messages(b, recs[i].at, recs[i].size);
    EXPECT_TRUE(m.has_value()) << "chunk at " << recs[i].at;
    if (!m) continue;
    n += m->size();
    std::set<std::tuple<uint16_t, uint64_t, uint64_t>> want(m->begin(), m->end()), got;
    for (size_t j = i + 1; j < recs.size() && recs[j].op == 0x07; ++j) {
      uint16_t ch = rd<uint16_t>(b, recs[j].at + 9);
      uint32_t len = rd<uint32_t>(b, recs[j].at + 11);
      for (size_t e = 0; e < len; e += 16)
        got.emplace(ch, rd<uint64_t>(b, recs[j].at + 15 + e), rd<uint64_t>(b, recs[j].at + 23 + e));
    }
    EXPECT_EQ(got, want) << "message indexes of the chunk at " << recs[i].at;
  }
  return n;
}

// 19 single-bit flips spread over the data, and 6 full-byte flips on the fields that frame
// a chunk or an index (opcode, record length, CRC, uncompressed size, an index's length and
// channel).
std::vector<std::pair<size_t, uint8_t>> flips(const Bytes& b, const std::vector<Record>& layout) {
  std::vector<size_t> chunks, indexes;
  for (const Record& r : layout) (r.op == 0x06 ? chunks : indexes).push_back(r.at);
  std::vector<std::pair<size_t, uint8_t>> out;
  size_t first = chunks.front();
  for (size_t k = 0; k < 19; ++k)
    out.emplace_back(first + 1 + k * (b.size() - first - 2) / 18,
                     static_cast<uint8_t>(1u << (k % 8)));
  auto after = [&](size_t chunk) {  // the first Message Index record after that chunk
    for (size_t at : indexes)
      if (at > chunks[chunk]) return at;
    return indexes.back();
  };
  out.emplace_back(chunks[3], 0xFF);
  out.emplace_back(chunks[5] + 1 + 2, 0xFF);
  out.emplace_back(chunks[7] + 9 + 24, 0xFF);
  out.emplace_back(chunks[9] + 9 + 16 + 3, 0xFF);
  out.emplace_back(after(11) + 1 + 1, 0xFF);
  out.emplace_back(after(13) + 9, 0xFF);
  return out;
}

// A crashed file in a fresh directory, with its undamaged layout.
struct Fixture {
  std::string dir;
  Bytes clean;
  std::vector<Record> layout;
  explicit Fixture(const std::string& name)
      : dir(fresh_dir(name)), clean(crashed_file(dir)), layout(records(clean)) {}
  ~Fixture() { std::filesystem::remove_all(dir); }
};

Recovered recover_one(const std::string& dir, const Bytes& b) {
  std::string path = dir + "/usv-crashed.mcap";
  spill(path, b);
  WriterOptions o;
  auto rs = recover_dir(dir, "usv", o);
  EXPECT_EQ(rs.size(), 1u);
  return rs.empty() ? Recovered{} : rs[0];
}

}  // namespace

TEST(McapRecoverDamage, EachOf25SingleByteFlipsKeepsEveryChunkWhoseDataChecks) {
  Fixture fx("flips");
  const auto& [dir, clean, layout] = std::tie(fx.dir, fx.clean, fx.layout);
  ASSERT_GT(
      std::count_if(layout.begin(), layout.end(), [](const Record& r) { return r.op == 0x06; }),
      30);
  const uint64_t all = oracle_count(clean, layout);
  int rewritten = 0;
  for (auto [at, mask] : flips(clean, layout)) {
    Bytes d = clean;
    d[at] ^= mask;
    uint64_t want = oracle_count(d, layout);
    Recovered r = recover_one(dir, d);
    ASSERT_FALSE(r.failed) << "flip at " << at;
    EXPECT_EQ(r.messages, want) << "flip at " << at;
    EXPECT_GE(want + 400, all);  // one chunk of ~100 messages at most per flip
    Bytes out = slurp(dir + "/usv-crashed.mcap");
    EXPECT_EQ(read_back(out), want) << "flip at " << at;
    rewritten += r.rewritten;
    if (want < all) { EXPECT_FALSE(r.skipped.empty()) << "flip at " << at; }
  }
  EXPECT_GT(rewritten, 10);  // most flips land before the last chunk: the copy path ran
}

TEST(McapRecoverDamage, All25FlipsInOneFileKeepEveryChunkWhoseDataChecks) {
  Fixture fx("flips-all");
  Bytes d = fx.clean;
  for (auto [at, mask] : flips(fx.clean, fx.layout)) d[at] ^= mask;
  uint64_t want = oracle_count(d, fx.layout);
  Recovered r = recover_one(fx.dir, d);
  EXPECT_TRUE(r.rewritten);
  EXPECT_EQ(r.messages, want);
  EXPECT_GE(r.skipped.size(), 10u);
  EXPECT_EQ(read_back(slurp(fx.dir + "/usv-crashed.mcap")), want);
}

// A flip the decoder reads past: the chunk's data still checks (this libzstd ignores, for
// one, the reserved bits of a block's Symbol_Compression_Modes, which zstd 1.5.7 refuses; the
// Python `mcap` reader then throws on the whole file). The chunk is kept and written anew from
// its data: every chunk of the recovered file is what the writer's zstd level 1 makes of it.
TEST(McapRecoverDamage, AFlipTheDecoderReadsPastIsWrittenAnewFromTheChunksData) {
  Fixture fx("read-past");
  std::vector<Record> chunks;
  for (const Record& r : fx.layout)
    if (r.op == 0x06) chunks.push_back(r);
  const Record& c = chunks[10];
  const auto want = chunk_messages(fx.clean, c.at, c.size);
  ASSERT_TRUE(want.has_value());
  std::optional<std::pair<size_t, uint8_t>> flip;
  for (size_t at = c.at + 9 + 44; at < c.at + c.size && !flip; ++at)
    for (int bit = 0; bit < 8 && !flip; ++bit) {
      Bytes d = fx.clean;
      d[at] ^= static_cast<uint8_t>(1u << bit);
      if (chunk_messages(d, c.at, c.size) == want) flip = {at, static_cast<uint8_t>(1u << bit)};
    }
  ASSERT_TRUE(flip.has_value()) << "no flip this libzstd reads past in the chunk";
  Bytes d = fx.clean;
  d[flip->first] ^= flip->second;
  const uint64_t all = oracle_count(fx.clean, fx.layout);
  ASSERT_EQ(oracle_count(d, fx.layout), all);

  Recovered r = recover_one(fx.dir, d);
  EXPECT_EQ(r.messages, all);
  EXPECT_EQ(r.skipped.size(), 1u);  // the torn tail, nothing else
  EXPECT_EQ(r.rewritten_chunks, 1u);
  EXPECT_TRUE(r.rewritten);  // not finished in place: that would keep the flip
  Bytes out = slurp(fx.dir + "/usv-crashed.mcap");
  EXPECT_EQ(read_back(out), all);
  size_t checked = 0;
  for (const Record& rec : records(out)) {
    if (rec.op != 0x06) continue;
    uint64_t usize = rd<uint64_t>(out, rec.at + 9 + 16);
    uint64_t clen = rd<uint64_t>(out, rec.at + 9 + 36);
    Bytes plain(usize), again(ZSTD_compressBound(usize));
    ASSERT_EQ(ZSTD_decompress(plain.data(), usize, &out[rec.at + 9 + 44], clen), usize);
    again.resize(ZSTD_compress(again.data(), again.size(), plain.data(), usize, 1));
    EXPECT_TRUE(Bytes(out.begin() + rec.at + 9 + 44, out.begin() + rec.at + 9 + 44 + clen) == again)
        << "chunk at " << rec.at;
    ++checked;
  }
  EXPECT_EQ(checked, chunks.size());

  Recovered clean = recover_one(fx.dir, fx.clean);  // the writer's own chunks stay as they are
  EXPECT_EQ(clean.rewritten_chunks, 0u);
  EXPECT_FALSE(clean.rewritten);
}

TEST(McapRecoverDamage, WithoutRoomForTheCopyTheOriginalStaysAsItIs) {
  Fixture fx("no-copy");
  Bytes d = fx.clean;
  d[fx.layout[4].at + 60] ^= 0x10;  // a damaged chunk early on: the copy path
  std::string path = fx.dir + "/usv-crashed.mcap";
  spill(path, d);
  std::filesystem::create_directory(path + ".recovering");  // the copy cannot be created
  EXPECT_THROW(recover_mcap(path, WriterOptions{}), modd::Error);
  EXPECT_EQ(slurp(path), d);
  std::filesystem::remove(path + ".recovering");
  Recovered r = recover_mcap(path, WriterOptions{});
  EXPECT_TRUE(r.rewritten);
  EXPECT_EQ(r.messages, oracle_count(d, fx.layout));
}

TEST(McapRecoverDamage, ACraftedHugeLengthOrSizeIsSkippedNotAllocated) {
  Fixture fx("huge");
  std::vector<size_t> chunks;
  for (const Record& r : fx.layout)
    if (r.op == 0x06) chunks.push_back(r.at);
  Bytes d = fx.clean;
  uint64_t huge = ~0ull >> 1;
  std::memcpy(&d[chunks[2] + 1], &huge, 8);       // record length
  std::memcpy(&d[chunks[6] + 9 + 16], &huge, 8);  // uncompressed size
  uint64_t want = oracle_count(d, fx.layout);
  Recovered r = recover_one(fx.dir, d);
  EXPECT_EQ(r.messages, want);
  EXPECT_EQ(read_back(slurp(fx.dir + "/usv-crashed.mcap")), want);
}

TEST(McapRecoverDamage, AFlippedMagicIsWrittenAgainNotTheFileRemoved) {
  Fixture fx("magic");
  Bytes d = fx.clean;
  d[3] ^= 0x20;  // "MCAP" -> "MCaP"
  uint64_t want = oracle_count(d, fx.layout);
  Recovered r = recover_one(fx.dir, d);
  EXPECT_FALSE(r.removed);
  EXPECT_TRUE(r.rewritten);
  EXPECT_EQ(r.messages, want);
  EXPECT_EQ(read_back(slurp(fx.dir + "/usv-crashed.mcap")), want);
}
