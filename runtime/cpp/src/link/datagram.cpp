#include "modd/link/datagram.hpp"

#include <algorithm>
#include <cstring>
#include <string>

#include "modd/link/auth.hpp"
#include "modd/util/bytes.hpp"

namespace modd::link::dgram {

namespace {

std::vector<uint8_t> tag(const Mac& key, uint8_t direction, uint64_t seq,
                         std::span<const uint8_t> body, size_t n) {
  std::vector<uint8_t> msg;
  msg.reserve(9 + body.size());
  msg.push_back(direction);
  for (int i = 0; i < 8; ++i) msg.push_back(static_cast<uint8_t>(seq >> (8 * i)));
  msg.insert(msg.end(), body.begin(), body.end());
  Mac full = hmac_sha256(key, msg);
  return {full.begin(), full.begin() + static_cast<long>(n)};
}

bool equal_ct(std::span<const uint8_t> a, std::span<const uint8_t> b) {
  if (a.size() != b.size()) return false;
  uint8_t d = 0;
  for (size_t i = 0; i < a.size(); ++i) d |= a[i] ^ b[i];
  return d == 0;
}

}  // namespace

Mac session_key(std::span<const uint8_t> psk, const Nonce& client, const Nonce& server) {
  std::vector<uint8_t> msg{'M', 'O', 'D', 'D', '1', 'K'};
  msg.insert(msg.end(), client.begin(), client.end());
  msg.insert(msg.end(), server.begin(), server.end());
  return hmac_sha256(psk, msg);
}

uint64_t extend16(uint16_t low, uint64_t expected) {
  int64_t base = static_cast<int64_t>(expected - (expected & 0xFFFF) + low);
  int64_t best = -1;
  for (int64_t c : {base - 0x10000, base, base + 0x10000}) {
    if (c < 0) continue;
    auto dist = [&](int64_t x) {
      return x > static_cast<int64_t>(expected) ? x - static_cast<int64_t>(expected)
                                                : static_cast<int64_t>(expected) - x;
    };
    if (best < 0 || dist(c) < dist(best)) best = c;
  }
  return static_cast<uint64_t>(best);
}

std::vector<uint8_t> encode_data(const DataDatagram& d, const Mac& key, uint8_t direction) {
  if (d.config_id == 0 || d.slots.empty()) throw std::invalid_argument("empty DATA datagram");
  std::vector<uint8_t> out;
  ByteWriter w(out);
  w.u8(d.presence.empty() ? kData : kDataBitmap);
  w.u8(d.config_id);
  w.u8(static_cast<uint8_t>(d.slot & 0xFF));
  w.u8(static_cast<uint8_t>((d.slot >> 8) & 0xFF));
  if (!d.presence.empty()) {
    if (d.slots.size() > kMaxDatagramSlots)
      throw std::invalid_argument("more than " + std::to_string(kMaxDatagramSlots) + " slots");
    w.u8(static_cast<uint8_t>(d.slots.size()));
    w.varint(d.presence.size());
    std::vector<uint8_t> bm((d.presence.size() + 7) / 8);
    for (size_t i = 0; i < d.presence.size(); ++i)
      if (d.presence[i]) bm[i / 8] |= static_cast<uint8_t>(1u << (i % 8));
    w.bytes(bm);
  }
  for (const auto& s : d.slots) w.bytes(s);
  auto t = tag(key, direction, d.slot, out, kTag);
  out.insert(out.end(), t.begin(), t.end());
  return out;
}

VerifiedData verify_data(std::span<const uint8_t> raw, const Mac& key, uint8_t direction,
                         uint64_t expected_slot) {
  if (raw.size() < 4 + kTag || (raw[0] != kData && raw[0] != kDataBitmap))
    throw Error(ErrorCode::BadFrame, "not a DATA datagram", 0);
  auto body = raw.first(raw.size() - kTag);
  uint16_t low = static_cast<uint16_t>(raw[2] | (raw[3] << 8));
  uint64_t slot = extend16(low, expected_slot);
  if (!equal_ct(tag(key, direction, slot, body, kTag), raw.last(kTag)))
    throw Forged("tag of the datagram of slot " + std::to_string(slot) + " does not verify");
  ByteReader r(body);
  r.u8();
  VerifiedData v;
  v.config_id = r.u8();
  r.bytes(2);
  v.slot = slot;
  if (raw[0] == kDataBitmap) {
    uint8_t count = r.u8();
    uint64_t streams = r.varint();
    if (count == 0 || streams > 8 * r.remaining())
      r.fail("presence bitmap longer than the datagram");
    auto bm = r.bytes(static_cast<size_t>((streams + 7) / 8));
    for (size_t i = streams; i < bm.size() * 8; ++i)
      if (bm[i / 8] >> (i % 8) & 1) r.fail("presence bit set beyond the datagram's streams");
    v.slot_count = count;
    v.stream_count = streams;
    v.presence.assign(bm.begin(), bm.end());
  }
  auto rest = r.bytes(r.remaining());
  v.values.assign(rest.begin(), rest.end());
  return v;
}

std::vector<uint8_t> slot_bitmap_body(const std::vector<bool>& presence,
                                      std::span<const uint8_t> values) {
  std::vector<uint8_t> out;
  ByteWriter w(out);
  w.u8(1);
  w.varint(presence.size());
  std::vector<uint8_t> bm((presence.size() + 7) / 8);
  for (size_t i = 0; i < presence.size(); ++i)
    if (presence[i]) bm[i / 8] |= static_cast<uint8_t>(1u << (i % 8));
  w.bytes(bm);
  w.bytes(values);
  return out;
}

std::vector<std::vector<uint8_t>> encode_fragments(uint8_t config_id, uint64_t slot,
                                                   std::span<const uint8_t> body,
                                                   size_t max_datagram, const Mac& key,
                                                   uint8_t direction) {
  if (config_id == 0 || max_datagram <= kFragmentHead + kTag || body.empty())
    throw std::invalid_argument("a fragment needs a config id, a body and room for a piece");
  size_t room = max_datagram - kFragmentHead - kTag;
  size_t count = (body.size() + room - 1) / room;
  if (count > kMaxFragments)
    throw std::invalid_argument("a slot of " + std::to_string(body.size()) + " B needs " +
                                std::to_string(count) + " fragments of " + std::to_string(room) +
                                " B (at most 16)");
  std::vector<std::vector<uint8_t>> out;
  for (size_t i = 0; i < count; ++i) {
    std::vector<uint8_t> d{kFragment, config_id, static_cast<uint8_t>(slot & 0xFF),
                           static_cast<uint8_t>((slot >> 8) & 0xFF),
                           static_cast<uint8_t>(i << 4 | (count - 1))};
    auto piece = body.subspan(i * room, std::min(room, body.size() - i * room));
    d.insert(d.end(), piece.begin(), piece.end());
    auto t = tag(key, direction, slot, d, kTag);
    d.insert(d.end(), t.begin(), t.end());
    out.push_back(std::move(d));
  }
  return out;
}

Fragment verify_fragment(std::span<const uint8_t> raw, const Mac& key, uint8_t direction,
                         uint64_t expected_slot) {
  if (raw.size() < kFragmentHead + 1 + kTag || raw[0] != kFragment)
    throw Error(ErrorCode::BadFrame, "not a fragment datagram", 0);
  auto body = raw.first(raw.size() - kTag);
  uint64_t slot = extend16(static_cast<uint16_t>(raw[2] | (raw[3] << 8)), expected_slot);
  if (!equal_ct(tag(key, direction, slot, body, kTag), raw.last(kTag)))
    throw Forged("tag of the fragment of slot " + std::to_string(slot) + " does not verify");
  Fragment f;
  f.config_id = raw[1];
  f.slot = slot;
  f.index = static_cast<uint8_t>(raw[4] >> 4);
  f.count = static_cast<uint8_t>((raw[4] & 0x0F) + 1);
  if (f.index >= f.count) throw Error(ErrorCode::BadFrame, "fragment index beyond its count", 4);
  auto piece = body.subspan(kFragmentHead);
  f.piece.assign(piece.begin(), piece.end());
  return f;
}

std::vector<uint8_t> encode_control(uint64_t counter, std::span<const uint8_t> frame,
                                    const Mac& key, uint8_t direction) {
  std::vector<uint8_t> out;
  ByteWriter w(out);
  w.u8(kControl);
  w.varint(counter);
  w.bytes(frame);
  auto t = tag(key, direction, counter, out, kControlTag);
  out.insert(out.end(), t.begin(), t.end());
  return out;
}

// A control datagram or control fragment (`kind`) whose tag verified: a reader of its body
// after the counter, and the counter. The tag is checked before anything after the counter
// is read.
static std::pair<ByteReader, uint64_t> verified_control(std::span<const uint8_t> raw,
                                                        const Mac& key, uint8_t direction,
                                                        uint8_t kind, size_t min_body,
                                                        const std::string& what) {
  if (raw.size() < min_body + kControlTag || raw[0] != kind)
    throw Error(ErrorCode::BadFrame, "not a " + what, 0);
  auto body = raw.first(raw.size() - kControlTag);
  ByteReader r(body);
  r.u8();
  uint64_t counter = r.varint();
  if (!equal_ct(tag(key, direction, counter, body, kControlTag), raw.last(kControlTag)))
    throw Forged("tag of " + what + " " + std::to_string(counter) + " does not verify");
  return {r, counter};
}

std::pair<uint64_t, std::vector<uint8_t>> verify_control(std::span<const uint8_t> raw,
                                                         const Mac& key, uint8_t direction) {
  auto [r, counter] = verified_control(raw, key, direction, kControl, 3, "control datagram");
  auto rest = r.bytes(r.remaining());
  return {counter, {rest.begin(), rest.end()}};
}

std::vector<std::vector<uint8_t>> encode_control_fragments(uint64_t counter,
                                                           std::span<const uint8_t> frames,
                                                           size_t max_datagram, const Mac& key,
                                                           uint8_t direction) {
  if (max_datagram <= kControlFragmentOverhead || frames.empty() ||
      counter + kMaxFragments >= (uint64_t{1} << 35))
    throw std::invalid_argument(
        "a control fragment needs frames, room for a piece and a counter below 2^35");
  size_t room = max_datagram - kControlFragmentOverhead;
  size_t count = (frames.size() + room - 1) / room;
  if (count > kMaxFragments)
    throw std::invalid_argument("a control message of " + std::to_string(frames.size()) +
                                " B needs " + std::to_string(count) + " fragments of " +
                                std::to_string(room) + " B (at most 16)");
  std::vector<std::vector<uint8_t>> out;
  for (size_t i = 0; i < count; ++i) {
    std::vector<uint8_t> d;
    ByteWriter w(d);
    w.u8(kControlFragment);
    w.varint(counter + i);
    w.u8(static_cast<uint8_t>(i << 4 | (count - 1)));
    w.bytes(frames.subspan(i * room, std::min(room, frames.size() - i * room)));
    auto t = tag(key, direction, counter + i, d, kControlTag);
    d.insert(d.end(), t.begin(), t.end());
    out.push_back(std::move(d));
  }
  return out;
}

ControlFragment verify_control_fragment(std::span<const uint8_t> raw, const Mac& key,
                                        uint8_t direction) {
  auto [r, counter] =
      verified_control(raw, key, direction, kControlFragment, 4, "control fragment");
  size_t at = r.pos();
  uint8_t frag = r.u8();
  ControlFragment f;
  f.counter = counter;
  f.index = frag >> 4;
  f.count = (frag & 0x0F) + 1u;
  if (f.index >= f.count || counter < f.index)
    throw Error(ErrorCode::BadFrame,
                "control fragment " + std::to_string(f.index) + " of " + std::to_string(f.count),
                at);
  auto rest = r.bytes(r.remaining());
  f.piece.assign(rest.begin(), rest.end());
  return f;
}

std::optional<std::vector<uint8_t>> ControlPieces::add(ControlFragment f) {
  auto it = partial_.find(f.first());
  if (it != partial_.end() && it->second.count != f.count) {
    ++malformed_;
    return std::nullopt;
  }
  if (it == partial_.end()) {
    if (f.count == 1) return std::move(f.piece);
    if (partial_.size() >= kMaxPartial) {  // the oldest message: given up
      partial_.erase(partial_.begin());
      ++given_up_;
    }
    it = partial_.emplace(f.first(), Partial{f.count, {}}).first;
  }
  Partial& p = it->second;
  p.pieces[f.index] = std::move(f.piece);
  if (p.pieces.size() < p.count) return std::nullopt;
  std::vector<uint8_t> whole;
  for (auto& [i, piece] : p.pieces) whole.insert(whole.end(), piece.begin(), piece.end());
  partial_.erase(it);
  return whole;
}

bool ReplayWindow::accept(uint64_t seq) {
  if ((any_ && top_ >= size_ && seq <= top_ - size_) || seen_.count(seq)) return false;
  seen_.insert(seq);
  if (!any_ || seq > top_) {
    top_ = seq;
    any_ = true;
    if (seen_.size() > size_ && top_ >= size_)
      seen_.erase(seen_.begin(), seen_.upper_bound(top_ - size_));
  }
  return true;
}

uint16_t crc16(std::span<const uint8_t> data) {
  uint16_t crc = 0xFFFF;
  for (uint8_t b : data) {
    crc ^= static_cast<uint16_t>(b << 8);
    for (int i = 0; i < 8; ++i)
      crc = (crc & 0x8000) ? static_cast<uint16_t>((crc << 1) ^ 0x1021)
                           : static_cast<uint16_t>(crc << 1);
  }
  return crc;
}

std::vector<uint8_t> cobs_encode(std::span<const uint8_t> data) {
  std::vector<uint8_t> out{0};
  size_t code_at = 0;
  for (uint8_t b : data) {
    if (b == 0) {
      out[code_at] = static_cast<uint8_t>(out.size() - code_at);
      code_at = out.size();
      out.push_back(0);
      continue;
    }
    out.push_back(b);
    if (out.size() - code_at == 0xFF) {
      out[code_at] = 0xFF;
      code_at = out.size();
      out.push_back(0);
    }
  }
  out[code_at] = static_cast<uint8_t>(out.size() - code_at);
  return out;
}

std::optional<std::vector<uint8_t>> cobs_decode(std::span<const uint8_t> data) {
  std::vector<uint8_t> out;
  size_t i = 0;
  while (i < data.size()) {
    uint8_t code = data[i];
    if (code == 0 || i + code > data.size()) return std::nullopt;
    for (size_t k = i + 1; k < i + code; ++k) {
      if (data[k] == 0) return std::nullopt;
      out.push_back(data[k]);
    }
    i += code;
    if (code != 0xFF && i < data.size()) out.push_back(0);
  }
  return out;
}

std::vector<uint8_t> encode_frame(std::span<const uint8_t> datagram) {
  std::vector<uint8_t> body(datagram.begin(), datagram.end());
  uint16_t crc = crc16(datagram);
  body.push_back(static_cast<uint8_t>(crc & 0xFF));
  body.push_back(static_cast<uint8_t>(crc >> 8));
  auto out = cobs_encode(body);
  out.push_back(0);
  return out;
}

std::vector<std::vector<uint8_t>> Deframer::feed(std::span<const uint8_t> bytes) {
  std::vector<std::vector<uint8_t>> out;
  for (uint8_t b : bytes) {
    if (b != 0) {
      if (skipping_) continue;
      buf_.push_back(b);
      if (buf_.size() > max_) {
        ++oversized_;
        buf_.clear();
        skipping_ = true;
      }
      continue;
    }
    if (skipping_) {
      skipping_ = false;
      continue;
    }
    if (buf_.empty()) continue;
    auto body = cobs_decode(buf_);
    buf_.clear();
    if (!body || body->size() < 3 ||
        crc16(std::span<const uint8_t>(*body).first(body->size() - 2)) !=
            static_cast<uint16_t>((*body)[body->size() - 2] | ((*body)[body->size() - 1] << 8))) {
      ++corrupt_;
      continue;
    }
    body->resize(body->size() - 2);
    out.push_back(std::move(*body));
  }
  return out;
}

}  // namespace modd::link::dgram
