#include "modd/link/backfill.hpp"

#include "modd/util/bytes.hpp"

namespace modd::link::backfill {

namespace {

void put_frame(std::vector<uint8_t>& out, Type type, const std::vector<uint8_t>& body) {
  ByteWriter w(out);
  w.varint(body.size() + 1);
  w.u8(static_cast<uint8_t>(type));
  w.bytes(body);
}

void check_windows(const ByteReader& r, uint64_t windows, uint64_t resume) {
  if (windows < 1 || windows > kMaxWindows)
    r.fail("window count " + std::to_string(windows) + " out of range");
  if (resume > windows)
    r.fail("resume point " + std::to_string(resume) + " beyond the " + std::to_string(windows) +
           " windows");
}

}  // namespace

bool is_backfill_type(uint8_t type) { return type >= 0x50 && type <= 0x54; }

void encode(std::vector<uint8_t>& out, const Message& m) {
  std::vector<uint8_t> body;
  ByteWriter w(body);
  Type type{};
  std::visit(
      [&](const auto& msg) {
        using T = std::decay_t<decltype(msg)>;
        if constexpr (std::is_same_v<T, Request>) {
          type = Type::Request;
          w.varint(msg.request_id);
          w.string(msg.topic);
          w.u8(static_cast<uint8_t>(msg.type));
          w.u8(static_cast<uint8_t>(msg.aggregation));
          w.varint(msg.period_us);
          if (msg.aggregation == Aggregation::Percentile) w.fixed<double>(msg.percentile);
          if (is_event(msg.aggregation)) {
            put_event_params(w, msg.aggregation, msg.event);
            w.fixed<uint64_t>(msg.state_from_ns);
          }
          w.fixed<uint64_t>(msg.from_ns);
          w.varint(msg.windows);
          w.varint(msg.resume);
          w.varint(msg.rate_bps);
        } else if constexpr (std::is_same_v<T, Progress>) {
          type = Type::Progress;
          w.varint(msg.request_id);
          w.varint(msg.next);
          w.varint(msg.windows);
          w.varint(msg.bytes_sent);
          w.varint(msg.rate_bps);
        } else if constexpr (std::is_same_v<T, End>) {
          type = Type::End;
          w.varint(msg.request_id);
          w.u8(static_cast<uint8_t>(msg.status));
          w.varint(msg.next);
          w.string(msg.message);
        } else {
          type = Type::Cancel;
          w.varint(msg.request_id);
        }
      },
      m);
  put_frame(out, type, body);
}

void encode_data(std::vector<uint8_t>& out, const DataFrame& d, const ValueKind& kind) {
  size_t n = d.values.size();
  if (n < 1 || n > kMaxBatch)
    throw Error(ErrorCode::Internal, "BACKFILL_DATA with " + std::to_string(n) + " windows");
  std::vector<uint8_t> body;
  ByteWriter w(body);
  w.varint(d.request_id);
  w.varint(d.first);
  w.varint(n);
  size_t at = body.size();
  body.resize(at + (n + 7) / 8, 0);
  for (size_t i = 0; i < n; ++i)
    if (d.values[i].present) body[at + i / 8] |= static_cast<uint8_t>(1u << (i % 8));
  for (const auto& v : d.values)
    if (v.present) encode_value(body, kind, v);
  put_frame(out, Type::Data, body);
}

Message decode(const RawFrame& f) {
  ByteReader r(f.body, 0);
  Message m;
  switch (static_cast<Type>(f.type)) {
    case Type::Request: {
      Request q;
      q.request_id = r.varint();
      q.topic = r.string(kMaxName);
      uint8_t ty = r.u8();
      if (ty >= kValueTypeCount) r.fail("unknown value type " + std::to_string(ty));
      q.type = static_cast<ValueType>(ty);
      uint8_t a = r.u8();
      if (a >= table::kAggregationCount) r.fail("unknown aggregation " + std::to_string(a));
      q.aggregation = static_cast<Aggregation>(a);
      q.period_us = r.varint();
      if (q.period_us < 1 || q.period_us > kMaxPeriodUs) r.fail("window period out of range");
      if (q.aggregation == Aggregation::Percentile) {
        q.percentile = r.fixed<double>();
        if (!(q.percentile >= 0 && q.percentile <= 100)) r.fail("percentile out of 0..100");
      }
      if (is_event(q.aggregation)) {
        q.event = get_event_params(r, q.aggregation, "request");
        q.state_from_ns = r.fixed<uint64_t>();
      }
      q.from_ns = r.fixed<uint64_t>();
      if (is_event(q.aggregation) && q.state_from_ns > q.from_ns)
        r.fail("the events' state starts after the first window");
      q.windows = r.varint();
      q.resume = r.varint();
      check_windows(r, q.windows, q.resume);
      q.rate_bps = r.varint();
      m = q;
      break;
    }
    case Type::Progress: {
      Progress p;
      p.request_id = r.varint();
      p.next = r.varint();
      p.windows = r.varint();
      check_windows(r, p.windows, p.next);
      p.bytes_sent = r.varint();
      p.rate_bps = r.varint();
      m = p;
      break;
    }
    case Type::End: {
      End e;
      e.request_id = r.varint();
      uint8_t st = r.u8();
      if (st > static_cast<uint8_t>(EndStatus::Io))
        r.fail("unknown backfill end status " + std::to_string(st));
      e.status = static_cast<EndStatus>(st);
      e.next = r.varint();
      e.message = r.string(1024);
      m = e;
      break;
    }
    case Type::Cancel: m = Cancel{r.varint()}; break;
    default:
      throw Error(ErrorCode::BadFrame, "not a backfill message type " + std::to_string(f.type), 0);
  }
  r.expect_end();
  return m;
}

uint64_t data_request_id(const RawFrame& f) {
  if (f.type != static_cast<uint8_t>(Type::Data))
    throw Error(ErrorCode::BadFrame, "not a BACKFILL_DATA frame", 0);
  ByteReader r(f.body, 0);
  return r.varint();
}

DataFrame decode_data(const RawFrame& f, const ValueKind& kind) {
  DataFrame d;
  d.request_id = data_request_id(f);
  ByteReader r(f.body, 0);
  r.varint();
  d.first = r.varint();
  uint64_t n = r.varint();
  if (n < 1 || n > kMaxBatch)
    r.fail("window count " + std::to_string(n) + " out of 1.." + std::to_string(kMaxBatch));
  if (d.first + n > kMaxWindows) r.fail("windows beyond the largest request");
  auto bm = r.bytes((n + 7) / 8);
  for (size_t i = n; i < bm.size() * 8; ++i)
    if ((bm[i / 8] >> (i % 8)) & 1) r.fail("presence bit set beyond the frame's windows");
  d.values.resize(n);
  for (size_t i = 0; i < n; ++i)
    if ((bm[i / 8] >> (i % 8)) & 1) d.values[i] = decode_value(r, kind);
  r.expect_end();
  return d;
}

}  // namespace modd::link::backfill
