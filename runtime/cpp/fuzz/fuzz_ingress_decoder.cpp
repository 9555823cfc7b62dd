// libFuzzer target: a publisher connection's bytes into the broker's ingress
// session (registration, records, validation, counting, archive hand-off).
#include <unistd.h>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>

#include "modd/broker/broker.hpp"

using namespace modd;
using namespace modd::broker;

namespace {
struct NoLink : LinkOutput {
  bool link_ready() const override { return false; }
  bool link_write(std::vector<uint8_t>&&) override { return false; }
};

// The archive of the fuzzed broker lives in a per-process directory removed at exit (this
// object is built before the broker, so it is destroyed after it).
struct ArchiveDir {
  std::string path =
      (std::filesystem::temp_directory_path() / ("modd-fuzz-ingress-" + std::to_string(getpid())))
          .string();
  ~ArchiveDir() { std::filesystem::remove_all(path); }
};

Broker& the_broker() {
  static ArchiveDir dir;
  static FakeClock clock;
  static NoLink link;
  static std::unique_ptr<Broker> b = [] {
    BrokerConfig cfg;
    cfg.archive_dir = dir.path;
    cfg.topics = {{"a", link::ValueType::Float32, 4},
                  {"b", link::ValueType::Int, 2},
                  {"c", link::ValueType::Bool, 1}};
    cfg.accept_unknown_topics = true;
    cfg.rotate_bytes = 1 << 20;
    cfg.queue_limit_samples = 10000;
    return std::make_unique<Broker>(cfg, "k", clock, link);
  }();
  return *b;
}

// The client's side: broker replies (CATALOGUE, ACK, REJECT) decoded from the same bytes.
struct Replies : ingress::ReplyHandler {
  size_t n = 0;
  void on_catalogue(const ingress::Catalogue&) override { ++n; }
  void on_ack(const ingress::Ack&) override { ++n; }
  void on_reject(const ingress::RejectMsg&) override { ++n; }
};

void decode_replies(std::span<const uint8_t> in, Replies& r, bool must_parse) {
  size_t used = 0;
  try {
    while (auto f = ingress::split_frame(in.subspan(used), ingress::kMaxFrame)) {
      used += f->size;
      ingress::decode_reply(*f, r);
    }
  } catch (const Error&) {
    if (must_parse) __builtin_trap();  // what the broker writes always decodes
  }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Broker& b = the_broker();
  Replies replies;
  decode_replies(std::span(data, size), replies, false);
  IngressSession s(b);
  // Feed in two pieces so that frames split across reads are exercised.
  size_t half = size / 2;
  if (s.on_bytes(std::span(data, half))) s.on_bytes(std::span(data + half, size - half));
  const Counters& c = b.counters();
  if (c.samples_in != c.accepted + c.rejected_total()) __builtin_trap();  // nothing uncounted
  // What the broker answers this publisher (catalogue, rejections, acknowledgement) decodes.
  s.checkpoint(1);
  s.report(1);
  auto out = s.take_output();
  decode_replies(out, replies, true);
  if (s.rejected() + s.accepted() > c.samples_in) __builtin_trap();
  return 0;
}
