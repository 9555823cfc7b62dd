// Structural checks of the MCAP writer (the official Python reader reads the
// files in tests/runtime): magic at both ends, footer -> summary, CRCs.
#include <gtest/gtest.h>
#include <lz4frame.h>
#include <zstd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>

#include "modd/archive/archiver.hpp"
#include "modd/archive/crc32.hpp"
#include "modd/archive/mcap_writer.hpp"
#include "modd/archive/recover.hpp"
#include "modd/util/error.hpp"

using namespace modd::archive;

namespace {

struct TempDirs {
  std::vector<std::string> dirs;
  ~TempDirs() {
    for (const auto& d : dirs) std::filesystem::remove_all(d);
  }
} temp_dirs;

std::string tmpdir(const std::string& name) {
  auto p = std::filesystem::temp_directory_path() /
           ("modd-test-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  temp_dirs.dirs.push_back(p);
  return p;
}

std::vector<uint8_t> slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), {}};
}

template <typename T>
T rd(const std::vector<uint8_t>& b, size_t at) {
  T v;
  std::memcpy(&v, b.data() + at, sizeof(T));
  return v;
}

const uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};

}  // namespace

TEST(Crc32, KnownValue) {
  const char* s = "123456789";
  EXPECT_EQ(crc32(0, std::span(reinterpret_cast<const uint8_t*>(s), 9)), 0xCBF43926u);
  auto a = std::span(reinterpret_cast<const uint8_t*>(s), 4),
       b = std::span(reinterpret_cast<const uint8_t*>(s + 4), 5);
  EXPECT_EQ(crc32(crc32(0, a), b), 0xCBF43926u);
}

// The table-driven CRC against the bit-by-bit definition, over every length and
// offset around the 16-byte stride, split at every point.
TEST(Crc32, MatchesBitwiseDefinition) {
  auto bitwise = [](std::span<const uint8_t> d) {
    uint32_t c = 0xFFFFFFFFu;
    for (uint8_t byte : d) {
      c ^= byte;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    }
    return ~c;
  };
  std::vector<uint8_t> buf(200);
  uint32_t x = 12345;
  for (auto& b : buf) b = static_cast<uint8_t>((x = x * 1103515245u + 12345u) >> 16);
  for (size_t off = 0; off < 17; ++off)
    for (size_t len = 0; off + len <= 90; ++len) {
      auto d = std::span<const uint8_t>(buf.data() + off, len);
      ASSERT_EQ(crc32(0, d), bitwise(d)) << "offset " << off << " length " << len;
      for (size_t cut = 0; cut <= len; cut += 7)
        ASSERT_EQ(crc32(crc32(0, d.first(cut)), d.subspan(cut)), bitwise(d)) << "cut " << cut;
    }
}

class McapWriterTest : public ::testing::TestWithParam<Compression> {};

TEST_P(McapWriterTest, FileStructureAndCrcs) {
  std::string dir = tmpdir("mcap");
  std::string path = dir + "/t.mcap";
  {
    WriterOptions o;
    o.compression = GetParam();
    o.chunk_bytes = 2000;                               // several chunks
    o.message_index = GetParam() != Compression::None;  // both layouts, across the parameters
    McapWriter w(path, o);
    uint16_t s = w.add_schema("modd.float32", "jsonschema",
                              sample_json_schema(modd::link::ValueType::Float32));
    uint16_t c0 = w.add_channel(s, "a", "json");
    uint16_t c1 = w.add_channel(s, "b", "json");
    std::string js;
    for (int i = 0; i < 300; ++i) {
      format_sample_json(js, modd::link::ValueType::Float32, Sample{i * 1000, i, i * 0.5, 0});
      w.add_message(i % 2 ? c1 : c0, static_cast<uint32_t>(i), 1000 + i, i,
                    std::span(reinterpret_cast<const uint8_t*>(js.data()), js.size()));
    }
    w.close();
    EXPECT_EQ(w.message_count(), 300u);
  }
  auto b = slurp(path);
  ASSERT_GT(b.size(), 100u);
  EXPECT_EQ(std::memcmp(b.data(), kMagic, 8), 0);
  EXPECT_EQ(std::memcmp(b.data() + b.size() - 8, kMagic, 8), 0);
  size_t footer = b.size() - 8 - (1 + 8 + 20);
  ASSERT_EQ(b[footer], 0x02);
  uint64_t summary_start = rd<uint64_t>(b, footer + 9);
  uint32_t summary_crc = rd<uint32_t>(b, footer + 9 + 16);
  ASSERT_LT(summary_start, footer);
  EXPECT_EQ(crc32(0, std::span(b.data() + summary_start, footer + 9 + 16 - summary_start)),
            summary_crc);
  // Walk the data section: every chunk's records decompress to their CRC.
  size_t at = 8;
  int chunks = 0;
  uint64_t messages = 0, indexed = 0;
  while (at < summary_start) {
    uint8_t op = b[at];
    uint64_t len = rd<uint64_t>(b, at + 1);
    size_t body = at + 9;
    if (op == 0x07) indexed += rd<uint32_t>(b, body + 2) / 16;  // message index entries
    if (op == 0x0F) {  // data end: CRC of everything before it
      EXPECT_EQ(rd<uint32_t>(b, body), crc32(0, std::span(b.data(), at)));
    }
    if (op == 0x06) {
      ++chunks;
      uint64_t usize = rd<uint64_t>(b, body + 16);
      uint32_t ucrc = rd<uint32_t>(b, body + 24);
      uint32_t clen = rd<uint32_t>(b, body + 28);
      std::string comp(reinterpret_cast<const char*>(b.data() + body + 32), clen);
      size_t rec_at = body + 32 + clen;
      uint64_t rlen = rd<uint64_t>(b, rec_at);
      const uint8_t* recs = b.data() + rec_at + 8;
      std::vector<uint8_t> plain(usize);
      if (comp == "zstd") {
        ASSERT_EQ(ZSTD_decompress(plain.data(), plain.size(), recs, rlen), usize);
      } else if (comp == "lz4") {
        LZ4F_dctx* ctx;
        LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION);
        size_t dst = usize, src = rlen;
        LZ4F_decompress(ctx, plain.data(), &dst, recs, &src, nullptr);
        LZ4F_freeDecompressionContext(ctx);
        ASSERT_EQ(dst, usize);
      } else {
        ASSERT_EQ(rlen, usize);
        std::memcpy(plain.data(), recs, usize);
      }
      EXPECT_EQ(crc32(0, plain), ucrc);
      for (size_t p = 0; p < plain.size();) {
        EXPECT_EQ(plain[p], 0x05);
        ++messages;
        p += 9 + rd<uint64_t>(plain, p + 1);
      }
    }
    at = body + len;
  }
  EXPECT_EQ(at, summary_start);
  EXPECT_GT(chunks, 2);
  EXPECT_EQ(messages, 300u);
  EXPECT_EQ(indexed, GetParam() != Compression::None ? 300u : 0u);
}

INSTANTIATE_TEST_SUITE_P(Compressions, McapWriterTest,
                         ::testing::Values(Compression::Zstd, Compression::Lz4, Compression::None));

TEST(Archiver, WritesEverythingSubmittedAndRotates) {
  std::string dir = tmpdir("archiver");
  ArchiverOptions o;
  o.dir = dir;
  o.rotate_bytes = 4000;
  o.writer.chunk_bytes = 1000;
  auto topic = std::make_shared<TopicInfo>(TopicInfo{"usv.x", modd::link::ValueType::Float64});
  {
    Archiver a(o);
    for (int b = 0; b < 50; ++b) {
      std::vector<Sample> v;
      for (int i = 0; i < 20; ++i) v.push_back({b * 100 + i, b * 100 + i, i * 0.25, 0});
      a.submit(topic, std::move(v));
    }
    a.flush();
    a.stop();
    EXPECT_EQ(a.counters().archived.load(), 1000u);
    EXPECT_EQ(a.counters().queued.load(), 0u);
    EXPECT_GT(a.counters().files.load(), 1u);
  }
  int files = 0;
  for (auto& e : std::filesystem::directory_iterator(dir)) {
    auto b = slurp(e.path());
    EXPECT_EQ(std::memcmp(b.data() + b.size() - 8, kMagic, 8), 0) << e.path();
    ++files;
  }
  EXPECT_GT(files, 1);
}

TEST(Archiver, JsonOfEachType) {
  std::string s;
  format_sample_json(s, modd::link::ValueType::Float32, Sample{0, 0, 0.1f, 0});
  EXPECT_EQ(s, "{\"value\":0.1}");
  format_sample_json(s, modd::link::ValueType::Int, Sample{0, 0, 0, -42});
  EXPECT_EQ(s, "{\"value\":-42}");
  format_sample_json(s, modd::link::ValueType::Bool, Sample{0, 0, 0, 1});
  EXPECT_EQ(s, "{\"value\":true}");
}

TEST(Archiver, RotatesByTime) {
  std::string dir = tmpdir("rotate-time");
  ArchiverOptions o;
  o.dir = dir;
  o.rotate_s = 1;
  auto topic = std::make_shared<TopicInfo>(TopicInfo{"usv.t", modd::link::ValueType::Int});
  Archiver a(o);
  a.submit(topic, std::vector<Sample>{{1, 1, 0, 7}});
  a.flush();
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  a.submit(topic, std::vector<Sample>{{2, 2, 0, 8}});  // older than 1 s: this file closes after it
  a.submit(topic, std::vector<Sample>{{3, 3, 0, 9}});  // a new file
  a.stop();
  EXPECT_EQ(a.counters().archived.load(), 3u);
  EXPECT_EQ(a.counters().files.load(), 2u);
}

TEST(Archiver, RotatesByChunkCountSoTheOpenSummaryIsBounded) {
  std::string dir = tmpdir("rotate-chunks");
  ArchiverOptions o;
  o.dir = dir;
  o.rotate_chunks = 2;  // the open file's chunk indexes: at most 2 held in memory
  auto topic = std::make_shared<TopicInfo>(TopicInfo{"usv.t", modd::link::ValueType::Int});
  Archiver a(o);
  for (int64_t i = 0; i < 6; ++i) {
    a.submit(topic, std::vector<Sample>{{i, i, 0, i}});
    a.flush();  // one chunk per sample
  }
  a.submit(topic, std::vector<Sample>{{7, 7, 0, 7}});
  a.stop();
  EXPECT_EQ(a.counters().archived.load(), 7u);
  EXPECT_GE(a.counters().files.load(), 3u);  // was 1: every chunk index held until the close
}

TEST(McapRecover, AFileCutByACrashKeepsItsCompleteChunksAndGetsASummary) {
  std::string dir = tmpdir("recover");
  std::string path = dir + "/usv-crash.mcap";
  WriterOptions o;
  o.chunk_bytes = 512;
  o.fsync = FsyncPolicy::Never;
  uint64_t flushed = 0;
  {
    McapWriter w(path, o);
    uint16_t s = w.add_schema("modd.float32", "jsonschema", "{}");
    uint16_t ch = w.add_channel(s, "usv.x", "json", {{"type", "float32"}});
    std::string m = "{\"value\":1.5}";
    for (uint32_t i = 0; i < 200; ++i)
      w.add_message(ch, i, 1000 + i, 900 + i,
                    std::span(reinterpret_cast<const uint8_t*>(m.data()), m.size()));
    flushed = w.flushed_messages();
    ASSERT_GT(flushed, 0u);
    ASSERT_LT(flushed, 200u);  // the last chunk is still open, as at a kill -9
    w.abandon();
  }
  auto bytes = slurp(path);
  std::filesystem::resize_file(path, bytes.size() - 5);  // a torn tail too
  EXPECT_FALSE(mcap_complete(path));
  auto rs = recover_dir(dir, "usv", o);
  ASSERT_EQ(rs.size(), 1u);
  EXPECT_TRUE(mcap_complete(path));
  EXPECT_LE(rs[0].messages, flushed);
  EXPECT_GE(rs[0].messages + 40, flushed);  // at most the torn chunk lost
  EXPECT_GT(rs[0].dropped_bytes, 0u);
  auto out = slurp(path);
  EXPECT_EQ(std::memcmp(out.data(), kMagic, 8), 0);
  EXPECT_EQ(std::memcmp(out.data() + out.size() - 8, kMagic, 8), 0);
  EXPECT_TRUE(recover_dir(dir, "usv", o).empty());  // complete now: left alone
}

TEST(McapWriter, AWriteErrorLosesNothingAndResumes) {
  // /dev/full fails every write with ENOSPC: what was not written stays pending.
  WriterOptions o;
  o.chunk_bytes = 64;
  McapWriter w("/dev/full", o);
  uint16_t ch = w.add_channel(0, "usv.x", "json");
  std::string m = "{\"value\":1}";
  EXPECT_THROW(for (uint32_t i = 0; i < 10; ++i) w.add_message(
                   ch, i, i, i, std::span(reinterpret_cast<const uint8_t*>(m.data()), m.size())),
               modd::Error);
  EXPECT_EQ(w.flushed_messages(), 0u);
  EXPECT_GT(w.pending_bytes(), 0u);
  uint64_t pending = w.pending_bytes();
  EXPECT_THROW(w.flush_chunk(), modd::Error);
  EXPECT_GE(w.pending_bytes(), pending);  // still held, to be written when space returns
  w.abandon();
}

TEST(McapRecover, AFileIsFinishedInPlaceAndAChunkWithoutAllItsIndexesGetsThemWrittenAgain) {
  std::string dir = tmpdir("recover-in-place");
  std::string path = dir + "/usv-cut.mcap";
  WriterOptions o;
  o.chunk_bytes = 512;
  o.fsync = FsyncPolicy::Never;
  uint64_t flushed = 0;
  {
    McapWriter w(path, o);
    uint16_t s = w.add_schema("modd.float32", "jsonschema", "{}");
    uint16_t a = w.add_channel(s, "usv.a", "json");
    uint16_t b = w.add_channel(s, "usv.b", "json");
    std::string m = "{\"value\":1.5}";
    for (uint32_t i = 0; i < 200;
         ++i)  // both channels in every chunk: two Message Index records each
      w.add_message(i % 2 ? a : b, i, 1000 + i, 900 + i,
                    std::span(reinterpret_cast<const uint8_t*>(m.data()), m.size()));
    w.flush_chunk();
    flushed = w.flushed_messages();
    w.abandon();
  }
  auto before = slurp(path);
  // Cut inside the last chunk's second Message Index record: that chunk is not whole.
  std::filesystem::resize_file(path, before.size() - 10);
  auto rs = recover_dir(dir, "usv", o);
  ASSERT_EQ(rs.size(), 1u);
  EXPECT_FALSE(rs[0].failed);
  EXPECT_FALSE(rs[0].rewritten);
  EXPECT_EQ(rs[0].messages,
            flushed);  // the last chunk's data checks: kept, its indexes written again
  auto after = slurp(path);
  uint64_t kept = before.size() - 10 - rs[0].dropped_bytes;
  // In place: the kept bytes are the original ones (up to the last chunk), then its indexes
  // as the writer had written them, then the summary.
  EXPECT_EQ(std::memcmp(after.data(), before.data(), before.size() - 10), 0);
  EXPECT_EQ(after[kept], 0x07);
  EXPECT_EQ(after[before.size()], 0x0F);  // Data End right after the last chunk and its indexes
  EXPECT_TRUE(mcap_complete(path));
  EXPECT_TRUE(std::filesystem::is_empty(dir) == false);
  EXPECT_TRUE(recover_dir(dir, "usv", o).empty());
}
