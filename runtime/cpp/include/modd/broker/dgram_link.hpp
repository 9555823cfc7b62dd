// The PubBroker's side of a datagram link (udp, serial; docs/protocol.md,
// "Datagram transports"), without the socket: the handshake in 0x41
// datagrams, the session key, CONTROL datagrams (PING, CONFIG, NACK, STATUS)
// under their tags and replay window, slot packing up to the accepted delay
// and the packet, the resend ring, and the keepalive timeout.
//
// Contract: everything received goes through on_datagram(); every slot the
// executor fires goes through add_slot() (empty ones too: the sequence has no
// holes); tick(now) sends a group whose first slot has waited the accepted
// delay. What leaves goes to a DatagramOut: `reply` datagrams to the sender
// of the datagram being handled, the others to the authenticated peer.
#pragma once
#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "modd/broker/link_session.hpp"
#include "modd/link/challenges.hpp"
#include "modd/link/datagram.hpp"
#include "modd/link/messages.hpp"
#include "modd/util/token_bucket.hpp"

namespace modd::broker {

class DatagramOut {
 public:
  virtual ~DatagramOut() = default;
  virtual void send(std::vector<uint8_t>&& datagram, bool reply) = 0;
  // The sender of the datagram being handled becomes the peer (udp: its address).
  virtual void adopt_source() = 0;
  // The sender of the datagram being handled (udp: its address bytes; serial: none), and
  // whether it is the peer: after AUTH, the session is bound to the peer's address.
  virtual std::vector<uint8_t> source() const { return {}; }
  virtual bool from_peer() const { return true; }
};

struct DgramOptions {
  size_t max_datagram = 1472;  // largest datagram (udp payload; serial: frame minus framing)
  int64_t delay_ns =
      1'000'000'000;  // accepted delay: a group is sent when its first slot waited this
  int64_t keepalive_timeout_ns = 90'000'000'000;  // silence after which DATA stops (3 x 30 s PING)
  size_t ring_datagrams = 256;
  size_t ring_bytes = 64 * 1024;
  // NACK resends: earned one byte per live DATA byte sent, from none (so resends never add
  // more than the plan's own bytes) up to `resend_burst_bytes`, and at most `resend_per_nack_bytes`
  // for one NACK (docs/protocol.md, "Resends"). 0: ring_bytes, ring_bytes / 4.
  size_t resend_burst_bytes = 0;
  size_t resend_per_nack_bytes = 0;
  link::ChallengeLimits challenges{};
};

struct DgramCounters {
  uint64_t datagrams_in = 0, datagrams_out = 0, bytes_out = 0;
  uint64_t forged = 0, replayed = 0, malformed = 0;
  uint64_t nacks = 0, resent = 0, too_old = 0;
  uint64_t handshakes = 0, timeouts = 0;
  uint64_t fragments = 0;  // 0x32 datagrams sent for slots larger than a packet
  uint64_t dropped =
      0;  // slots not sent: no session, or too large for 16 fragments (archived all the same)
  uint64_t foreign = 0;  // datagrams of the session from another address than its peer's: dropped
  uint64_t resend_paced =
      0;  // NACKed datagrams not resent: over the resend budget (asked again later)
};

class DatagramLink {
 public:
  DatagramLink(std::string psk, LinkHooks& hooks, DatagramOut& out, DgramOptions opt,
               std::optional<link::Mac> cookie_secret = std::nullopt);

  void on_datagram(std::span<const uint8_t> raw, int64_t now);
  // One fired slot: its values encoded as in DATA (no seq8, no bitmap) and one
  // presence flag per stream of the slot. False when no session is up. enc (slots
  // with quantised streams) writes them again against the open datagram's chain.
  bool add_slot(uint8_t config_id, uint64_t slot, int64_t date_ns, std::vector<uint8_t>&& values,
                std::vector<bool>&& presence, link::SlotEncoder&& enc = {});
  // A link frame (STATUS) in a CONTROL datagram; false when no session is up.
  bool send_frame(std::span<const uint8_t> frame);
  void tick(int64_t now);
  int64_t next_due_ns() const;
  bool ready() const { return ready_; }
  int64_t delay_ns() const { return delay_ns_; }  // the accepted delay packing runs with
  const DgramCounters& counters() const { return c_; }
  const link::ChallengeCounters& handshake_counters() const { return challenges_.counters(); }
  std::string summary() const;

 private:
  struct SlotEntry {
    std::vector<uint8_t> values;
    std::vector<bool> presence;
  };
  // One ring entry: a DATA datagram, or every fragment of one slot (frag_body set).
  struct Sent {
    uint64_t first = 0, count = 0, key_epoch = 0;
    link::dgram::DataDatagram d;
    std::vector<uint8_t> frag_body;
    std::vector<std::vector<uint8_t>> raws;
    size_t bytes() const;
  };
  void on_handshake(std::span<const uint8_t> frame, int64_t now);
  void on_control(std::span<const uint8_t> raw, int64_t now);
  void on_control_fragment(std::span<const uint8_t> raw, int64_t now);
  void on_control_frame(const std::vector<uint8_t>& frame);  // one control message's frame
  void on_nack(std::span<const uint8_t> body);
  void send_control(std::span<const uint8_t> frame, bool reply = false);
  void send_handshake(const link::Message& m, bool reply);
  size_t group_size(const SlotEntry* extra) const;
  static size_t alone_size(const SlotEntry& e);  // the datagram of this slot alone
  void flush();
  void send_fragments(uint8_t config_id, uint64_t slot, const SlotEntry& e);
  void keep(Sent&& s);
  void retag(Sent& s);
  void emit(std::vector<uint8_t>&& d, bool reply = false);

  std::string psk_;
  LinkHooks& hooks_;
  DatagramOut& out_;
  DgramOptions opt_;
  int64_t delay_ns_;  // the running accepted delay: the CONFIG's, else opt_.delay_ns
  DgramCounters c_;
  // handshakes in progress (several at once, rate-limited) and the session
  link::Challenges challenges_;
  bool ready_ = false;
  link::Mac key_{};
  uint64_t key_epoch_ = 0;
  link::Nonce session_client_{}, session_server_{};
  int64_t last_heard_ = 0;
  uint64_t counter_ = 0;
  link::dgram::ReplayWindow control_window_{64};
  link::dgram::ControlPieces pieces_;  // control messages cut into fragments (0x42)
  std::vector<uint8_t> last_config_, last_ack_;
  // packing
  uint8_t group_config_ = 0;
  uint64_t group_first_ = 0;
  int64_t group_date_ = 0;
  std::vector<SlotEntry> group_;
  link::Chain chain_;  // the open datagram's last steps by stream (quantised streams)
  bool joins_group(uint8_t config_id, uint64_t slot, int64_t date_ns) const;
  // resend ring
  std::deque<Sent> ring_;
  size_t ring_bytes_ = 0;
  // The first slot last kept per config id: a smaller one is a new config under that id.
  std::array<int64_t, 256> kept_first_ = filled(-1);
  static std::array<int64_t, 256> filled(int64_t v) {
    std::array<int64_t, 256> a;
    a.fill(v);
    return a;
  }
  void forget_config(uint8_t config_id);
  TokenBucket resend_budget_;
  size_t per_nack_;
};

// Largest datagram whose serial frame (COBS over datagram + CRC-16, then 0x00)
// fits a radio packet of `packet` bytes.
size_t serial_capacity(size_t packet);
// Bytes a datagram link adds on the wire to one frame sent in a CONTROL datagram of at
// most one packet: the datagram's type, counter (4 bytes: up to 2^28 datagrams) and tag,
// then IPv4 + UDP headers, or the serial framing (CRC-16, COBS code byte, delimiter).
// The backfill pace counts them (tcp: BackfillSender::kSegmentOverhead).
size_t control_frame_overhead(bool serial);
// Bytes of link frames one CONTROL datagram of `max_datagram` bytes carries whole (type,
// counter up to 2^35, tag): a STATUS that fits is never cut into control fragments.
size_t control_frame_room(size_t max_datagram);

}  // namespace modd::broker
