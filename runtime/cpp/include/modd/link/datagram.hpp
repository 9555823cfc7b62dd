// Datagram form of the MoDD link (udp and serial transports; docs/protocol.md,
// "Datagram transports"): DATA datagrams of consecutive slots with a truncated
// HMAC-SHA256 tag under the session key, control datagrams, the replay window,
// and the serial framing (COBS over datagram + CRC-16, then 0x00).
// The tag is verified before anything is decoded: a forged, reflected or
// corrupt datagram raises Forged and is counted, never decoded.
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <stdexcept>
#include <vector>

#include "modd/link/messages.hpp"

namespace modd::link::dgram {

// Datagram types, tag sizes and fragment limits: modd/link/wire.gen.hpp (wire.json).
constexpr uint8_t kDroneToBase = 'D';
constexpr uint8_t kBaseToDrone = 'B';

struct Forged : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// HMAC-SHA256(psk, "MODD1K" || client nonce || server nonce).
Mac session_key(std::span<const uint8_t> psk, const Nonce& client, const Nonce& server);
// The full slot congruent to `low` mod 2^16 nearest to `expected`.
uint64_t extend16(uint16_t low, uint64_t expected);

// A DATA datagram: slots `slot`, `slot + 1`, ... as encoded values (each the
// body of a DATA frame after seq8 and bitmap); `presence` empty when every
// stream of every slot is present, else one flag per stream of the slots.
struct DataDatagram {
  uint8_t config_id = 0;
  uint64_t slot = 0;
  std::vector<std::vector<uint8_t>> slots;
  std::vector<bool> presence;
};

std::vector<uint8_t> encode_data(const DataDatagram& d, const Mac& key, uint8_t direction);

struct VerifiedData {
  uint8_t config_id = 0;
  uint64_t slot = 0;
  std::optional<uint8_t> slot_count;  // none: all present, count while decoding
  std::vector<uint8_t> presence;      // bitmap bytes (0x31)
  uint64_t stream_count = 0;
  std::vector<uint8_t> values;
};
// Throws Forged (tag) or Error(BadFrame) with the offset in the datagram.
VerifiedData verify_data(std::span<const uint8_t> raw, const Mac& key, uint8_t direction,
                         uint64_t expected_slot);

// A slot too large for one packet goes as fragments (0x32) of its one-slot
// 0x31 body (k = 1, stream count, presence bitmap, values): at most 16 pieces,
// each datagram at most `max_datagram` bytes, each tagged with the full slot.
// Throws std::invalid_argument when 16 pieces cannot hold it.
std::vector<uint8_t> slot_bitmap_body(const std::vector<bool>& presence,
                                      std::span<const uint8_t> values);
std::vector<std::vector<uint8_t>> encode_fragments(uint8_t config_id, uint64_t slot,
                                                   std::span<const uint8_t> body,
                                                   size_t max_datagram, const Mac& key,
                                                   uint8_t direction);
struct Fragment {
  uint8_t config_id = 0;
  uint64_t slot = 0;
  uint8_t index = 0, count = 0;
  std::vector<uint8_t> piece;
};
// Throws Forged (tag) or Error(BadFrame).
Fragment verify_fragment(std::span<const uint8_t> raw, const Mac& key, uint8_t direction,
                         uint64_t expected_slot);

std::vector<uint8_t> encode_control(uint64_t counter, std::span<const uint8_t> frame,
                                    const Mac& key, uint8_t direction);
// (counter, frame) of a control datagram whose tag verifies.
std::pair<uint64_t, std::vector<uint8_t>> verify_control(std::span<const uint8_t> raw,
                                                         const Mac& key, uint8_t direction);

// RFC 4303-style window of sequence numbers seen (bounded by `size`).
// A control fragment (0x42) whose tag verified: piece `index` of `count` of the control
// message whose first fragment has counter `counter - index` (docs/protocol.md).
struct ControlFragment {
  uint64_t counter = 0;
  unsigned index = 0;
  unsigned count = 0;
  std::vector<uint8_t> piece;
  uint64_t first() const { return counter - index; }
};
// Bytes of a control fragment around its piece: type, counter (varint of at most 5 bytes:
// counters below 2^35), frag, tag.
constexpr size_t kControlFragmentOverhead = 1 + 5 + 1 + kControlTag;
// The 0x42 datagrams of a control message too large for one datagram: `frames` cut in
// order into at most 16 pieces, piece i under counter `counter + i`, each datagram at most
// `max_datagram` bytes. Throws std::invalid_argument beyond 16 pieces.
std::vector<std::vector<uint8_t>> encode_control_fragments(uint64_t counter,
                                                           std::span<const uint8_t> frames,
                                                           size_t max_datagram, const Mac& key,
                                                           uint8_t direction);
// Throws Forged (tag) or Error(BadFrame) with the offset in the datagram.
ControlFragment verify_control_fragment(std::span<const uint8_t> raw, const Mac& key,
                                        uint8_t direction);

// Control messages put back together from their fragments, bounded: at most kMaxPartial
// messages in progress (the oldest given up), kMaxFragments pieces each. add() returns the
// message's frames once every piece is there; a piece whose count differs from its
// message's is counted malformed and dropped. Replays are the replay window's business.
class ControlPieces {
 public:
  static constexpr size_t kMaxPartial = 4;
  std::optional<std::vector<uint8_t>> add(ControlFragment f);
  uint64_t malformed() const { return malformed_; }
  uint64_t given_up() const { return given_up_; }
  void clear() { partial_.clear(); }

 private:
  struct Partial {
    unsigned count = 0;
    std::map<unsigned, std::vector<uint8_t>> pieces;
  };
  std::map<uint64_t, Partial> partial_;  // by the message's first counter
  uint64_t malformed_ = 0, given_up_ = 0;
};

class ReplayWindow {
 public:
  explicit ReplayWindow(uint64_t size = 1024) : size_(size) {}
  bool accept(uint64_t seq);

 private:
  uint64_t size_;
  uint64_t top_ = 0;
  bool any_ = false;
  std::set<uint64_t> seen_;
};

// Serial framing.
uint16_t crc16(std::span<const uint8_t> data);  // CRC-16/CCITT-FALSE
std::vector<uint8_t> cobs_encode(std::span<const uint8_t> data);
std::optional<std::vector<uint8_t>> cobs_decode(std::span<const uint8_t> data);
std::vector<uint8_t> encode_frame(std::span<const uint8_t> datagram);

// Splits a serial byte stream into datagrams; frames longer than max_frame,
// malformed or failing the CRC are dropped and counted.
class Deframer {
 public:
  explicit Deframer(size_t max_frame) : max_(max_frame) {}
  std::vector<std::vector<uint8_t>> feed(std::span<const uint8_t> bytes);
  uint64_t corrupt() const { return corrupt_; }
  uint64_t oversized() const { return oversized_; }

 private:
  size_t max_;
  std::vector<uint8_t> buf_;
  bool skipping_ = false;
  uint64_t corrupt_ = 0, oversized_ = 0;
};

}  // namespace modd::link::dgram
