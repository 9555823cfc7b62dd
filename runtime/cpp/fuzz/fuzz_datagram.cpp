// libFuzzer target: the datagram transports' receive path (tag check of DATA,
// fragment, control and control fragment datagrams, fragment cutting and putting back
// together, the serial deframer, COBS, the PubBroker's handshake) fed arbitrary bytes. Must
// never crash, leak or hit UB; nothing unauthenticated is ever returned.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <span>

#include "modd/broker/dgram_link.hpp"
#include "modd/link/datagram.hpp"
#include "modd/util/error.hpp"

using namespace modd;
using namespace modd::link::dgram;

namespace {

// The PubBroker's datagram session fed whatever arrives, under no session: handshakes
// (HELLO floods, AUTHs against the outstanding challenges), and no key. Nothing may open
// a session without the key.
struct NoHooks : broker::LinkHooks {
  link::ConfigAck on_config(const link::Config& c) override { return {c.config_id, 0, 0}; }
  link::AuthOk current_config() override { return {}; }
  void on_authenticated() override { std::abort(); }
  void on_rejected(const std::string&) override {}
};
struct Sink : broker::DatagramOut {
  void send(std::vector<uint8_t>&&, bool) override {}
  void adopt_source() override {}
};

void fuzz_session(std::span<const uint8_t> in) {
  static NoHooks hooks;
  static Sink out;
  static broker::DatagramLink session("a-link-key-of-32-bytes-for-fuzzing", hooks, out, {},
                                      link::Mac{});
  static int64_t now = 0;
  now += 7'000'000;  // 7 ms a datagram: rate limits and expiry are exercised
  session.on_datagram(in, now);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::span<const uint8_t> in(data, size);
  const link::Mac key{};
  try {
    verify_data(in, key, kDroneToBase, 70000);
    // 2^-32 per input: a verifying random datagram would be a finding worth seeing
    std::abort();
  } catch (const Forged&) {
  } catch (const Error&) {}
  try {
    verify_control(in, key, kBaseToDrone);
    std::abort();
  } catch (const Forged&) {
  } catch (const Error&) {}
  try {
    verify_fragment(in, key, kDroneToBase, 70000);
    std::abort();
  } catch (const Forged&) {
  } catch (const Error&) {}
  try {
    verify_control_fragment(in, key, kBaseToDrone);
    std::abort();
  } catch (const Forged&) {
  } catch (const Error&) {}
  // control messages cut and put back together, in reverse order, bounded: the frames
  // come back whole, each datagram within the packet
  if (size > 0) {
    size_t max = 16 + data[0] % 240;
    try {
      auto frags = encode_control_fragments(1000 + size, in, max, key, kBaseToDrone);
      ControlPieces pieces;
      std::optional<std::vector<uint8_t>> whole;
      for (size_t k = frags.size(); k-- > 0;) {
        if (frags[k].size() > max || whole) std::abort();
        whole = pieces.add(verify_control_fragment(frags[k], key, kBaseToDrone));
      }
      if (!whole || *whole != std::vector<uint8_t>(in.begin(), in.end())) std::abort();
    } catch (const std::invalid_argument&) {}
  }
  // the sender's cutting: pieces put back together give the body, each within the packet
  if (size > 0) {
    size_t max = 10 + data[0] % 240;
    try {
      auto frags = encode_fragments(1, 70000, in, max, key, kDroneToBase);
      std::vector<uint8_t> whole;
      for (const auto& f : frags) {
        if (f.size() > max) std::abort();
        auto got = verify_fragment(f, key, kDroneToBase, 70001);
        whole.insert(whole.end(), got.piece.begin(), got.piece.end());
      }
      if (whole != std::vector<uint8_t>(in.begin(), in.end())) std::abort();
    } catch (const std::invalid_argument&) {}
  }
  fuzz_session(in);
  Deframer df(252);
  for (const auto& d : df.feed(in)) {
    if (d.size() > 252) std::abort();
  }
  (void)cobs_decode(in);
  return 0;
}
