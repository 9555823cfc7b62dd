#include <gtest/gtest.h>

#include "modd/broker/config.hpp"
#include "modd/util/error.hpp"

using namespace modd;
using namespace modd::broker;

namespace {
std::string error_of(const std::string& json) {
  try {
    parse_config(json, "f.json");
  } catch (const Error& e) { return e.what(); }
  return "";
}
}  // namespace

TEST(Config, ParsesEveryKey) {
  auto c = parse_config(R"({
    "name": "usv",
    "link": {"host": "127.0.0.1", "port": 7171, "key": "env:K", "handshake_timeout_ms": 900},
    "ingress": {"unix_path": "/tmp/x.sock", "host": "127.0.0.1", "port": 7373},
    "archive": {"dir": "/tmp/a", "prefix": "p", "rotate_bytes": 1000000, "rotate_s": 60, "fsync": "never",
                "compression": "lz4", "chunk_bytes": 4096, "flush_interval_ms": 500, "queue_limit_samples": 99},
    "topics": [{"name": "usv.a.x", "type": "float64", "buffer_size": 28}, {"name": "usv.a.y"}],
    "default_buffer_size": 7, "accept_unknown_topics": true, "status_period_s": 5, "log_period_s": 0
  })",
                        "t");
  EXPECT_EQ(c.link_port, 7171);
  EXPECT_EQ(c.key_ref, "env:K");
  EXPECT_EQ(c.ingress_port, 7373);
  EXPECT_EQ(c.compression, archive::Compression::Lz4);
  EXPECT_EQ(c.fsync, archive::FsyncPolicy::Never);
  ASSERT_EQ(c.topics.size(), 2u);
  EXPECT_EQ(c.topics[0].type, link::ValueType::Float64);
  EXPECT_EQ(c.topics[1].type, link::ValueType::Float32);
  EXPECT_EQ(c.default_buffer_size, 7u);
  EXPECT_TRUE(c.accept_unknown_topics);
}

TEST(Config, ErrorsNameTheFileAndPointer) {
  std::string base =
      R"("link": {"key": "env:K"}, "ingress": {"port": 1}, "archive": {"dir": "/tmp/a"})";
  EXPECT_EQ(error_of("{" + base + "}"), "");
  EXPECT_NE(error_of("{" + base + R"(, "bogus": 1})").find("f.json: /bogus: unknown key"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"link": {}, "ingress": {"port": 1}, "archive": {"dir": "/a"}})")
                .find("/link/key"),
            std::string::npos);
  EXPECT_NE(error_of("{" + base + R"(, "topics": [{"name": "a", "type": "float16"}]})")
                .find("/topics/0/type"),
            std::string::npos);
  EXPECT_NE(
      error_of(
          R"({"link": {"key": "env:K", "port": 70000}, "ingress": {"port": 1}, "archive": {"dir": "/a"}})")
          .find("/link/port"),
      std::string::npos);
  EXPECT_NE(error_of("{ nope").find("f.json"), std::string::npos);
}
