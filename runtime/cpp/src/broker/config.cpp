#include "modd/broker/config.hpp"

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "modd/link/wire.gen.hpp"  // packet bounds and defaults (wire.json)
#include "modd/util/error.hpp"

namespace modd::broker {

using nlohmann::json;

namespace {

struct Ctx {
  const std::string& origin;
  [[noreturn]] void fail(const std::string& ptr, const std::string& what) const {
    throw Error(ErrorCode::BadConfig, origin + ": " + ptr + ": " + what);
  }
};

template <typename T>
void get(const Ctx& c, const json& obj, const std::string& ptr, const char* key, T& out) {
  if (!obj.contains(key)) return;
  const json& v = obj.at(key);
  std::string p = ptr + "/" + key;
  if constexpr (std::is_same_v<T, std::string>) {
    if (!v.is_string()) c.fail(p, "expected a string");
    out = v.get<std::string>();
  } else if constexpr (std::is_same_v<T, bool>) {
    if (!v.is_boolean()) c.fail(p, "expected true or false");
    out = v.get<bool>();
  } else {
    if (!v.is_number_integer() || v.get<int64_t>() < 0)
      c.fail(p, "expected a non-negative integer");
    uint64_t x = v.get<uint64_t>();
    if (x > static_cast<uint64_t>(std::numeric_limits<T>::max())) c.fail(p, "value too large");
    out = static_cast<T>(x);
  }
}

void check_keys(const Ctx& c, const json& obj, const std::string& ptr,
                std::initializer_list<const char*> keys) {
  if (!obj.is_object()) c.fail(ptr.empty() ? "/" : ptr, "expected an object");
  for (const auto& [k, _] : obj.items()) {
    bool known = false;
    for (const char* kk : keys) known = known || k == kk;
    if (!known) c.fail(ptr + "/" + k, "unknown key");
  }
}

}  // namespace

BrokerConfig parse_config(const std::string& text, const std::string& origin) {
  Ctx c{origin};
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    throw Error(ErrorCode::BadConfig,
                origin + ": byte " + std::to_string(e.byte) + ": " + e.what());
  }
  BrokerConfig cfg;
  check_keys(c, j, "",
             {"name", "link", "ingress", "archive", "topics", "default_buffer_size",
              "accept_unknown_topics", "status_period_s", "log_period_s", "log", "backfill"});
  get(c, j, "", "name", cfg.name);
  get(c, j, "", "default_buffer_size", cfg.default_buffer_size);
  get(c, j, "", "accept_unknown_topics", cfg.accept_unknown_topics);
  get(c, j, "", "status_period_s", cfg.status_period_s);
  if (j.contains("backfill")) {
    check_keys(c, j["backfill"], "/backfill", {"default_rate_bps"});
    get(c, j["backfill"], "/backfill", "default_rate_bps", cfg.backfill_default_rate_bps);
    if (cfg.backfill_default_rate_bps < 1)
      c.fail("/backfill/default_rate_bps", "must be at least 1");
  }
  get(c, j, "", "log_period_s", cfg.log_period_s);
  if (j.contains("log")) {
    const json& lg = j["log"];
    check_keys(c, lg, "/log", {"file", "max_bytes", "keep"});
    get(c, lg, "/log", "file", cfg.log_file);
    get(c, lg, "/log", "max_bytes", cfg.log_max_bytes);
    get(c, lg, "/log", "keep", cfg.log_keep);
    if (cfg.log_max_bytes < 4096) c.fail("/log/max_bytes", "must be at least 4096");
  }
  if (cfg.default_buffer_size < 1) c.fail("/default_buffer_size", "must be at least 1");
  if (!j.contains("link")) c.fail("/link", "missing (the link endpoint and key are required)");
  const json& l = j["link"];
  check_keys(c, l, "/link",
             {"host", "port", "key", "handshake_timeout_ms", "transport", "device", "baud",
              "max_packet", "delay_ms", "keepalive_timeout_s", "ring_bytes"});
  get(c, l, "/link", "transport", cfg.link_transport);
  if (cfg.link_transport != "tcp" && cfg.link_transport != "udp" && cfg.link_transport != "serial")
    c.fail("/link/transport", "expected tcp, udp or serial");
  get(c, l, "/link", "device", cfg.link_device);
  if (cfg.link_transport == "serial" && cfg.link_device.empty())
    c.fail("/link/device", "missing: a serial link needs the radio's device, e.g. /dev/ttyUSB0");
  get(c, l, "/link", "baud", cfg.link_baud);
  get(c, l, "/link", "max_packet", cfg.link_max_packet);
  namespace dg = modd::link::dgram;
  if (cfg.link_max_packet == 0)
    cfg.link_max_packet =
        cfg.link_transport == "serial" ? dg::kDefaultSerialPacket : dg::kDefaultUdpPacket;
  if (cfg.link_max_packet < dg::kMinPacket || cfg.link_max_packet > dg::kMaxPacket)
    c.fail("/link/max_packet",
           "expected " + std::to_string(dg::kMinPacket) + ".." + std::to_string(dg::kMaxPacket));
  get(c, l, "/link", "delay_ms", cfg.link_delay_ms);
  if (cfg.link_delay_ms > 3'600'000) c.fail("/link/delay_ms", "above one hour");
  get(c, l, "/link", "keepalive_timeout_s", cfg.link_keepalive_timeout_s);
  get(c, l, "/link", "ring_bytes", cfg.link_ring_bytes);
  if (cfg.link_ring_bytes < 256 || cfg.link_ring_bytes > (16u << 20))
    c.fail("/link/ring_bytes", "expected 256..16777216");
  get(c, l, "/link", "host", cfg.link_host);
  get(c, l, "/link", "port", cfg.link_port);
  get(c, l, "/link", "key", cfg.key_ref);
  get(c, l, "/link", "handshake_timeout_ms", cfg.handshake_timeout_ms);
  if (cfg.key_ref.empty()) c.fail("/link/key", "missing: a key reference env:NAME or file:PATH");
  if (j.contains("ingress")) {
    const json& i = j["ingress"];
    check_keys(c, i, "/ingress",
               {"unix_path", "host", "port", "max_future_ms", "max_past_ms",
                "publisher_quota_samples", "topic_quota_samples"});
    get(c, i, "/ingress", "max_future_ms", cfg.max_future_ms);
    get(c, i, "/ingress", "max_past_ms", cfg.max_past_ms);
    get(c, i, "/ingress", "publisher_quota_samples", cfg.publisher_quota_samples);
    get(c, i, "/ingress", "topic_quota_samples", cfg.topic_quota_samples);
    if (cfg.max_future_ms > 100ull * 365 * 86400 * 1000)
      c.fail("/ingress/max_future_ms", "above 100 years");
    if (cfg.max_past_ms > 100ull * 365 * 86400 * 1000)
      c.fail("/ingress/max_past_ms", "above 100 years");
    get(c, i, "/ingress", "unix_path", cfg.ingress_unix);
    get(c, i, "/ingress", "host", cfg.ingress_host);
    get(c, i, "/ingress", "port", cfg.ingress_port);
  }
  if (cfg.ingress_unix.empty() && cfg.ingress_port == 0)
    c.fail("/ingress", "needs unix_path or port");
  if (!j.contains("archive")) c.fail("/archive", "missing");
  const json& a = j["archive"];
  check_keys(c, a, "/archive",
             {"dir", "prefix", "rotate_bytes", "rotate_s", "fsync", "compression", "chunk_bytes",
              "flush_interval_ms", "queue_limit_samples", "message_index", "low_space_mb",
              "retry_max_ms"});
  get(c, a, "/archive", "low_space_mb", cfg.low_space_mb);
  get(c, a, "/archive", "retry_max_ms", cfg.retry_max_ms);
  if (cfg.retry_max_ms < 250) c.fail("/archive/retry_max_ms", "must be at least 250");
  get(c, a, "/archive", "dir", cfg.archive_dir);
  if (cfg.archive_dir.empty()) c.fail("/archive/dir", "missing");
  get(c, a, "/archive", "prefix", cfg.archive_prefix);
  get(c, a, "/archive", "rotate_bytes", cfg.rotate_bytes);
  get(c, a, "/archive", "rotate_s", cfg.rotate_s);
  get(c, a, "/archive", "chunk_bytes", cfg.chunk_bytes);
  get(c, a, "/archive", "message_index", cfg.message_index);
  get(c, a, "/archive", "flush_interval_ms", cfg.flush_interval_ms);
  get(c, a, "/archive", "queue_limit_samples", cfg.queue_limit_samples);
  if (cfg.flush_interval_ms < 10) c.fail("/archive/flush_interval_ms", "must be at least 10");
  // Readers (recovery, backfill) refuse a chunk over 256 MiB as a torn header: bound it here.
  if (cfg.chunk_bytes > (64u << 20)) c.fail("/archive/chunk_bytes", "must be at most 67108864");
  std::string s;
  get(c, a, "/archive", "fsync", s);
  if (!s.empty() && !archive::parse_fsync(s, cfg.fsync))
    c.fail("/archive/fsync", "expected never, chunk or close");
  s.clear();
  get(c, a, "/archive", "compression", s);
  if (!s.empty() && !archive::parse_compression(s, cfg.compression))
    c.fail("/archive/compression", "expected zstd, lz4 or none");
  if (j.contains("topics")) {
    if (!j["topics"].is_array()) c.fail("/topics", "expected an array");
    for (size_t n = 0; n < j["topics"].size(); ++n) {
      std::string p = "/topics/" + std::to_string(n);
      const json& t = j["topics"][n];
      check_keys(c, t, p, {"name", "type", "buffer_size"});
      TopicDefault td;
      get(c, t, p, "name", td.name);
      if (td.name.empty()) c.fail(p + "/name", "missing");
      std::string ty = "float32";
      get(c, t, p, "type", ty);
      if (!link::parse_value_type(ty, td.type))
        c.fail(p + "/type", "expected float32, float64, int or bool");
      get(c, t, p, "buffer_size", td.buffer_size);
      cfg.topics.push_back(td);
    }
  }
  return cfg;
}

BrokerConfig load_config(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw Error(ErrorCode::BadConfig, path + ": cannot open");
  std::ostringstream ss;
  ss << f.rdbuf();
  return parse_config(ss.str(), path);
}

}  // namespace modd::broker
