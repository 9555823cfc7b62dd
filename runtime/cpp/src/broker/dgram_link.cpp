#include "modd/broker/dgram_link.hpp"

#include <algorithm>
#include <cstdio>

#include "modd/link/auth.hpp"
#include "modd/link/backfill.hpp"
#include "modd/link/codec.hpp"
#include "modd/util/bytes.hpp"
#include "modd/util/log.hpp"

namespace modd::broker {

using namespace modd::link;
namespace dg = modd::link::dgram;

namespace {

size_t varint_size(uint64_t v) {
  size_t n = 1;
  while (v >= 0x80) {
    v >>= 7;
    ++n;
  }
  return n;
}

size_t serial_frame_bytes(size_t payload) {
  size_t body = payload + 2;
  return body + 1 + body / 254 + 1;
}

}  // namespace

size_t serial_capacity(size_t packet) {
  size_t n = packet > 4 ? packet - 4 : 0;
  while (n > 0 && serial_frame_bytes(n) > packet) --n;
  return n;
}

size_t control_frame_overhead(bool serial) {
  constexpr size_t kDatagram = 1 + 4 + dg::kControlTag;
  constexpr size_t kUdpIp = 28;  // IPv4 20 + UDP 8
  return kDatagram + (serial ? serial_frame_bytes(0) : kUdpIp);
}

size_t control_frame_room(size_t max_datagram) {
  constexpr size_t kHeader = 1 + 5 + dg::kControlTag;
  return max_datagram > kHeader ? max_datagram - kHeader : 0;
}

DatagramLink::DatagramLink(std::string psk, LinkHooks& hooks, DatagramOut& out, DgramOptions opt,
                           std::optional<Mac> cookie_secret)
    : psk_(std::move(psk)),
      hooks_(hooks),
      out_(out),
      opt_(opt),
      delay_ns_(opt.delay_ns),
      challenges_(std::span(reinterpret_cast<const uint8_t*>(psk_.data()), psk_.size()),
                  opt.challenges, cookie_secret),
      resend_budget_(
          0, static_cast<double>(opt.resend_burst_bytes ? opt.resend_burst_bytes : opt.ring_bytes),
          0),
      per_nack_(opt.resend_per_nack_bytes ? opt.resend_per_nack_bytes : opt.ring_bytes / 4) {}

void DatagramLink::emit(std::vector<uint8_t>&& d, bool reply) {
  ++c_.datagrams_out;
  c_.bytes_out += d.size();
  out_.send(std::move(d), reply);
}

void DatagramLink::on_datagram(std::span<const uint8_t> raw, int64_t now) {
  ++c_.datagrams_in;
  if (raw.empty()) {
    ++c_.malformed;
    return;
  }
  try {
    if (raw[0] == dg::kHandshake) {
      on_handshake(raw.subspan(1), now);
    } else if (raw[0] == dg::kControl) {
      on_control(raw, now);
    } else if (raw[0] == dg::kControlFragment) {
      on_control_fragment(raw, now);
    } else {
      ++c_.malformed;  // DATA goes drone -> base only
    }
  } catch (const dg::Forged&) { ++c_.forged; } catch (const Error&) {
    ++c_.malformed;
  }
}

void DatagramLink::send_handshake(const Message& m, bool reply) {
  std::vector<uint8_t> d{dg::kHandshake};
  encode(d, m);
  emit(std::move(d), reply);
}

void DatagramLink::on_handshake(std::span<const uint8_t> frame, int64_t now) {
  auto f = split_frame(frame, 64);
  if (!f || f->size != frame.size()) throw Error(ErrorCode::BadFrame, "not one handshake frame", 0);
  Message m = decode(*f);
  std::span<const uint8_t> key(reinterpret_cast<const uint8_t*>(psk_.data()), psk_.size());
  if (auto* h = std::get_if<Hello>(&m)) {
    if (h->version != kVersion) {
      send_handshake(
          ErrorMsg{static_cast<uint8_t>(ErrorCode::Version),
                   "unsupported version " + std::to_string(h->version) + ", this broker speaks 1"},
          true);
      return;
    }
    // A cookie: a repeated HELLO (its answer was lost) gets the same CHALLENGE. Over a
    // rate limit, no answer (bounded air time); the HELLO is remembered all the same.
    if (auto c = challenges_.on_hello(h->nonce, out_.source(), now))
      send_handshake(Challenge{kVersion, *c}, true);
    return;
  }
  auto* a = std::get_if<Auth>(&m);
  if (!a) throw Error(ErrorCode::BadFrame, "unexpected handshake frame", 0);
  if (ready_ && out_.from_peer() &&
      macs_equal(a->mac, client_proof(key, session_client_, session_server_))) {
    // AUTH repeated because AUTH_OK was lost: answer again, to the peer only.
    AuthOk ok = hooks_.current_config();
    ok.mac = server_proof(key, session_client_, session_server_);
    send_handshake(ok, false);
    return;
  }
  auto got = challenges_.on_auth(a->mac, out_.source(), now);
  if (got.status == Challenges::AuthResult::Limited) return;  // an AUTH flood: no air time
  if (got.status == Challenges::AuthResult::Failed) {
    hooks_.on_rejected("datagram AUTH does not verify (wrong key, or a stale challenge)");
    send_handshake(
        ErrorMsg{static_cast<uint8_t>(ErrorCode::AuthFailed), "HMAC proof does not verify"}, true);
    return;
  }
  session_client_ = got.hello;
  session_server_ = got.challenge;
  key_ = dg::session_key(key, session_client_, session_server_);
  ++key_epoch_;
  ready_ = true;
  last_heard_ = now;
  control_window_ = dg::ReplayWindow(64);
  pieces_.clear();
  ++c_.handshakes;
  out_.adopt_source();
  AuthOk ok = hooks_.current_config();
  ok.mac = server_proof(key, session_client_, session_server_);
  send_handshake(ok, true);
  hooks_.on_authenticated();
}

void DatagramLink::on_control(std::span<const uint8_t> raw, int64_t now) {
  if (!ready_) {
    ++c_.forged;  // no session: nothing can verify
    return;
  }
  if (!out_.from_peer()) {
    ++c_.foreign;  // the session is bound to its peer's address (a new AUTH moves it)
    return;
  }
  auto [counter, frame] = dg::verify_control(raw, key_, dg::kBaseToDrone);
  if (!control_window_.accept(counter)) {
    ++c_.replayed;
    return;
  }
  last_heard_ = now;
  on_control_frame(frame);
}

void DatagramLink::on_control_fragment(std::span<const uint8_t> raw, int64_t now) {
  if (!ready_) {
    ++c_.forged;  // no session: nothing can verify
    return;
  }
  if (!out_.from_peer()) {
    ++c_.foreign;  // the session is bound to its peer's address (a new AUTH moves it)
    return;
  }
  dg::ControlFragment piece = dg::verify_control_fragment(raw, key_, dg::kBaseToDrone);
  if (!control_window_.accept(piece.counter)) {
    ++c_.replayed;
    return;
  }
  last_heard_ = now;
  uint64_t before = pieces_.malformed();
  auto whole = pieces_.add(std::move(piece));
  c_.malformed += pieces_.malformed() - before;
  if (whole) on_control_frame(*whole);
}

void DatagramLink::on_control_frame(const std::vector<uint8_t>& frame) {
  auto f = split_frame(frame);
  if (!f || f->size != frame.size()) throw Error(ErrorCode::BadFrame, "not one control frame", 0);
  if (f->type == dg::kNack) {
    on_nack(f->body);
    return;
  }
  if (link::backfill::is_backfill_type(
          f->type)) {  // request or cancel (docs/protocol.md, "Backfill")
    std::vector<uint8_t> out;
    hooks_.on_backfill(*f, out);
    if (!out.empty()) send_control(out);
    return;
  }
  if (is_data_type(f->type)) throw Error(ErrorCode::BadFrame, "DATA in a control datagram", 0);
  Message m = decode(*f);
  if (auto* p = std::get_if<Ping>(&m)) {
    std::vector<uint8_t> out;
    encode(out, Pong{p->payload});
    send_control(out);
  } else if (auto* cfg = std::get_if<Config>(&m)) {
    if (frame == last_config_) {
      send_control(last_ack_);  // a retry: its ack was lost
      return;
    }
    ConfigAck ack = hooks_.on_config(*cfg);
    std::vector<uint8_t> out;
    encode(out, ack);
    if (ack.status == 0) {
      last_config_ = frame;
      last_ack_ = out;
      // a deploy may change the accepted delay: packing follows it from now on
      // (absent: the config file's), the group being packed included
      delay_ns_ =
          cfg->accepted_delay_ms ? int64_t{*cfg->accepted_delay_ms} * 1'000'000 : opt_.delay_ns;
    }
    send_control(out);
  } else if (auto* o = std::get_if<Onboard>(&m)) {
    if (auto ack = hooks_.on_onboard(*o)) {
      std::vector<uint8_t> out;
      encode(out, *ack);
      send_control(out);
    }
  } else if (auto* e = std::get_if<ErrorMsg>(&m)) {
    hooks_.on_rejected("peer sent ERROR " + std::to_string(e->code) + ": " + e->message);
    ready_ = false;
  }
}

void DatagramLink::on_nack(std::span<const uint8_t> body) {
  ByteReader r(body);
  uint64_t n = r.varint();
  if (n < 1 || n > dg::kMaxNackRanges)
    r.fail("a NACK holds 1.." + std::to_string(dg::kMaxNackRanges) + " ranges");
  ++c_.nacks;
  std::vector<std::pair<uint64_t, uint64_t>> ranges;
  for (uint64_t i = 0; i < n; ++i) {
    uint64_t first = r.varint(), count = r.varint();
    if (count < 1 || count > dg::kMaxNackRangeSlots)
      r.fail("NACK range of 0 or more than " + std::to_string(dg::kMaxNackRangeSlots) + " slots");
    ranges.emplace_back(first, count);
  }
  // Paced: at most per_nack_ bytes for this NACK and what live DATA has earned; what does
  // not fit is asked again by the base station's next NACK (or its backfill).
  size_t left = per_nack_;
  std::vector<const Sent*> done;  // a datagram once per NACK, however many ranges name it
  for (auto [first, count] : ranges) {
    if (ring_.empty() || first < ring_.front().first) ++c_.too_old;
    for (Sent& s : ring_) {
      if (s.first >= first + count || first >= s.first + s.count) continue;
      if (std::find(done.begin(), done.end(), &s) != done.end()) continue;
      done.push_back(&s);
      size_t n = s.bytes();
      if (n > left || !resend_budget_.take(last_heard_, static_cast<double>(n))) {
        c_.resend_paced += s.raws.size();
        continue;
      }
      left -= n;
      if (s.key_epoch != key_epoch_) retag(s);  // sent under an older session
      for (const auto& raw : s.raws) {
        ++c_.resent;
        emit(std::vector<uint8_t>(raw));
      }
    }
  }
}

void DatagramLink::send_control(std::span<const uint8_t> frame, bool reply) {
  auto d = dg::encode_control(counter_ + 1, frame, key_, dg::kDroneToBase);
  if (d.size() <= opt_.max_datagram) {
    ++counter_;
    emit(std::move(d), reply);
    return;
  }
  // larger than one packet (a backfill END with a long reason): control fragments
  std::vector<std::vector<uint8_t>> pieces;
  try {
    pieces = dg::encode_control_fragments(counter_ + 1, frame, opt_.max_datagram, key_,
                                          dg::kDroneToBase);
  } catch (const std::invalid_argument& e) {
    log_line("link: a control frame of %zu B not sent: %s", frame.size(), e.what());
    return;
  }
  counter_ += pieces.size();
  for (auto& p : pieces) emit(std::move(p), reply);
}

bool DatagramLink::send_frame(std::span<const uint8_t> frame) {
  if (!ready_) return false;
  send_control(frame);
  return true;
}

size_t DatagramLink::alone_size(const SlotEntry& e) {
  bool all = true;
  for (bool p : e.presence) all = all && p;
  size_t streams = e.presence.size();
  return 4 + (all ? 0 : 1 + varint_size(streams) + (streams + 7) / 8) + e.values.size() + dg::kTag;
}

size_t DatagramLink::group_size(const SlotEntry* extra) const {
  size_t values = 0, streams = 0;
  bool all = true;
  auto add = [&](const SlotEntry& e) {
    values += e.values.size();
    streams += e.presence.size();
    for (bool p : e.presence) all = all && p;
  };
  for (const auto& e : group_) add(e);
  if (extra) add(*extra);
  size_t head = 4 + (all ? 0 : 1 + varint_size(streams) + (streams + 7) / 8);
  return head + values + dg::kTag;
}

size_t DatagramLink::Sent::bytes() const {
  size_t n = 0;
  for (const auto& r : raws) n += r.size();
  return n;
}

void DatagramLink::retag(Sent& s) {  // tagged again under the current session's key
  if (s.frag_body.empty())
    s.raws = {dg::encode_data(s.d, key_, dg::kDroneToBase)};
  else
    s.raws = dg::encode_fragments(s.d.config_id, s.first, s.frag_body, opt_.max_datagram, key_,
                                  dg::kDroneToBase);
  s.key_epoch = key_epoch_;
}

void DatagramLink::keep(Sent&& s) {
  // A config id names one config at a time, and a NACK names slots alone: a new config
  // that reuses an id (another SubBroker's, one restarted: its ids start again) starts
  // its slots again, and the older config's datagrams under that id must not answer its
  // NACKs (the base station would decode them as the new config's slots).
  int64_t& last = kept_first_[s.d.config_id];
  if (static_cast<int64_t>(s.first) <= last) forget_config(s.d.config_id);
  last = static_cast<int64_t>(s.first);
  ring_bytes_ += s.bytes();
  ring_.push_back(std::move(s));
  while (!ring_.empty() && (ring_.size() > opt_.ring_datagrams || ring_bytes_ > opt_.ring_bytes)) {
    ring_bytes_ -= ring_.front().bytes();
    ring_.pop_front();
  }
}

void DatagramLink::forget_config(uint8_t config_id) {
  std::erase_if(ring_, [&](const Sent& e) {
    if (e.d.config_id != config_id) return false;
    ring_bytes_ -= e.bytes();
    return true;
  });
}

void DatagramLink::send_fragments(uint8_t config_id, uint64_t slot, const SlotEntry& e) {
  Sent s;
  s.first = slot;
  s.count = 1;
  s.key_epoch = key_epoch_;
  s.d.config_id = config_id;
  s.d.slot = slot;
  s.frag_body = dg::slot_bitmap_body(e.presence, e.values);
  try {
    s.raws = dg::encode_fragments(config_id, slot, s.frag_body, opt_.max_datagram, key_,
                                  dg::kDroneToBase);
  } catch (const std::invalid_argument& err) {
    // Lost to the live view only (the archive has every sample); the planner refuses such a
    // plan, so this is a config the planner did not check. Counted, logged once per 100.
    if (c_.dropped++ % 100 == 0)
      log_line("link: slot %llu dropped: %s", static_cast<unsigned long long>(slot), err.what());
    return;
  }
  for (const auto& raw : s.raws) {
    ++c_.fragments;
    resend_budget_.earn(static_cast<double>(raw.size()));
    emit(std::vector<uint8_t>(raw));
  }
  keep(std::move(s));
}

bool DatagramLink::joins_group(uint8_t config_id, uint64_t slot, int64_t date_ns) const {
  return !group_.empty() && config_id == group_config_ && slot == group_first_ + group_.size() &&
         date_ns - group_date_ <= delay_ns_ && group_.size() < 255;
}

bool DatagramLink::add_slot(uint8_t config_id, uint64_t slot, int64_t date_ns,
                            std::vector<uint8_t>&& values, std::vector<bool>&& presence,
                            link::SlotEncoder&& enc) {
  if (!ready_) {
    if (!group_.empty()) flush();
    ++c_.dropped;
    return false;
  }
  SlotEntry e{std::move(values), std::move(presence)};  // values: against an empty chain
  if (alone_size(e) > opt_.max_datagram) {
    flush();  // the slots before it go first, in order
    send_fragments(config_id, slot, e);
    return true;
  }
  // A slot that starts a datagram is written against an empty chain (e.values as
  // given); one that joins the open datagram, against its chain.
  bool joins = joins_group(config_id, slot, date_ns);
  link::Chain chain;
  if (enc && joins) {
    link::Chain joined = chain_;
    std::vector<uint8_t> delta = enc(joined);
    if (group_size(&e) - e.values.size() + delta.size() <= opt_.max_datagram) {
      e.values = std::move(delta);
      chain = std::move(joined);
    } else {
      joins = false;  // starts the next datagram
      enc(chain);
    }
  } else if (enc) {
    enc(chain);
  }
  if (!group_.empty() && (!joins || group_size(&e) > opt_.max_datagram)) flush();
  if (enc) chain_ = std::move(chain);
  if (group_.empty()) {
    group_config_ = config_id;
    group_first_ = slot;
    group_date_ = date_ns;
  }
  group_.push_back(std::move(e));
  return true;
}

void DatagramLink::flush() {
  if (group_.empty()) return;
  Sent s;
  s.first = group_first_;
  s.count = group_.size();
  s.key_epoch = key_epoch_;
  s.d.config_id = group_config_;
  s.d.slot = group_first_;
  bool all = true;
  for (const auto& e : group_)
    for (bool p : e.presence) all = all && p;
  for (auto& e : group_) {
    s.d.slots.push_back(std::move(e.values));
    if (!all) s.d.presence.insert(s.d.presence.end(), e.presence.begin(), e.presence.end());
  }
  group_.clear();
  chain_ = link::Chain{};
  if (!ready_) return;
  s.raws = {dg::encode_data(s.d, key_, dg::kDroneToBase)};
  resend_budget_.earn(static_cast<double>(s.raws[0].size()));
  emit(std::vector<uint8_t>(s.raws[0]));
  keep(std::move(s));
}

void DatagramLink::tick(int64_t now) {
  if (!group_.empty() && now - group_date_ >= delay_ns_) flush();
  if (ready_ && opt_.keepalive_timeout_ns > 0 && now - last_heard_ > opt_.keepalive_timeout_ns) {
    ready_ = false;
    ++c_.timeouts;
    log_line(
        "link: nothing authenticated from the base station for %lld s: DATA paused until a new "
        "handshake",
        static_cast<long long>((now - last_heard_) / 1'000'000'000));
  }
}

int64_t DatagramLink::next_due_ns() const {
  int64_t next = INT64_MAX;
  if (!group_.empty()) next = group_date_ + delay_ns_;
  if (ready_ && opt_.keepalive_timeout_ns > 0)
    next = std::min(next, last_heard_ + opt_.keepalive_timeout_ns + 1);
  return next;
}

std::string DatagramLink::summary() const {
  char buf[800];
  std::snprintf(
      buf, sizeof buf,
      "datagrams_in=%llu datagrams_out=%llu bytes_out=%llu forged=%llu replayed=%llu "
      "malformed=%llu "
      "nacks=%llu resent=%llu too_old=%llu handshakes=%llu timeouts=%llu fragments=%llu "
      "dropped=%llu "
      "foreign=%llu resend_paced=%llu challenges=%llu hellos_unanswered=%llu "
      "keyed_hellos=%llu stale_keyed=%llu",
      static_cast<unsigned long long>(c_.datagrams_in),
      static_cast<unsigned long long>(c_.datagrams_out),
      static_cast<unsigned long long>(c_.bytes_out), static_cast<unsigned long long>(c_.forged),
      static_cast<unsigned long long>(c_.replayed), static_cast<unsigned long long>(c_.malformed),
      static_cast<unsigned long long>(c_.nacks), static_cast<unsigned long long>(c_.resent),
      static_cast<unsigned long long>(c_.too_old), static_cast<unsigned long long>(c_.handshakes),
      static_cast<unsigned long long>(c_.timeouts), static_cast<unsigned long long>(c_.fragments),
      static_cast<unsigned long long>(c_.dropped), static_cast<unsigned long long>(c_.foreign),
      static_cast<unsigned long long>(c_.resend_paced),
      static_cast<unsigned long long>(challenges_.counters().challenges),
      static_cast<unsigned long long>(challenges_.counters().unanswered),
      static_cast<unsigned long long>(challenges_.counters().keyed),
      static_cast<unsigned long long>(challenges_.counters().stale_keyed));
  return buf;
}

}  // namespace modd::broker
