#include "modd/link/codec.hpp"

#include <cmath>
#include <cstdint>

#include "modd/util/bytes.hpp"

namespace modd::link {

namespace {

void put_frame(std::vector<uint8_t>& out, MsgType type, const std::vector<uint8_t>& body) {
  ByteWriter w(out);
  w.varint(body.size() + 1);
  w.u8(static_cast<uint8_t>(type));
  w.bytes(body);
}

template <size_t N>
void get_array(ByteReader& r, std::array<uint8_t, N>& a) {
  auto b = r.bytes(N);
  std::copy(b.begin(), b.end(), a.begin());
}

void put_scalar(ByteWriter& w, ScalarKind k, double number, int64_t integer, uint64_t count) {
  switch (k) {
    case ScalarKind::F32: w.fixed<float>(static_cast<float>(number)); break;
    case ScalarKind::F64: w.fixed<double>(number); break;
    case ScalarKind::ZigZag: w.svarint(integer); break;
    case ScalarKind::Bool: w.u8(integer ? 1 : 0); break;
    case ScalarKind::UVarint: w.varint(count); break;
  }
}

// An event window (docs/protocol.md, "Event values"): count, each event's time (µs after
// the window's start) and value, the coalesced count.
void put_events(ByteWriter& w, const ValueKind& k, const Value& v) {
  bool is_float = k.scalar == ScalarKind::F32 || k.scalar == ScalarKind::F64;
  size_t n = v.times_us.size();
  if ((is_float ? v.numbers.size() : v.integers.size()) != n)
    throw Error(ErrorCode::Internal, "event values and times differ in number");
  w.varint(n);
  for (size_t i = 0; i < n; ++i) {
    w.varint(v.times_us[i]);
    put_scalar(w, k.scalar, is_float ? v.numbers[i] : 0, is_float ? 0 : v.integers[i], 0);
  }
  w.varint(v.coalesced);
}

void get_scalar(ByteReader& r, ScalarKind k, double& number, int64_t& integer, uint64_t& count);

Value get_events(ByteReader& r, const ValueKind& k) {
  Value v;
  v.present = true;
  uint64_t n = r.varint();
  if (n < 1 || n > events::kMaxEvents || n > r.remaining())
    r.fail("event count " + std::to_string(n) + " out of 1.." + std::to_string(events::kMaxEvents) +
           " or beyond the frame");
  bool is_float = k.scalar == ScalarKind::F32 || k.scalar == ScalarKind::F64;
  for (uint64_t i = 0; i < n; ++i) {
    v.times_us.push_back(r.varint());
    double d = 0;
    int64_t x = 0;
    uint64_t c = 0;
    get_scalar(r, k.scalar, d, x, c);
    if (is_float)
      v.numbers.push_back(d);
    else
      v.integers.push_back(x);
  }
  v.coalesced = r.varint();
  v.count = n + v.coalesced;
  return v;
}

// chain: the unit's last steps by stream, for a kind with a declared resolution.
void put_value(ByteWriter& w, const ValueKind& k, const Value& v, Chain& chain, uint32_t stream) {
  bool quantised = k.resolution > 0;
  if (is_event(k.aggregation)) return put_events(w, k, v);
  if (k.aggregation == Aggregation::All) {
    bool is_float = k.scalar == ScalarKind::F32 || k.scalar == ScalarKind::F64;
    size_t n = is_float ? v.numbers.size() : v.integers.size();
    w.varint(n);
    for (size_t i = 0; i < n; ++i) {
      if (quantised)
        put_number(w, chain, stream, v.numbers[i], k.resolution);
      else
        put_scalar(w, k.scalar, is_float ? v.numbers[i] : 0, is_float ? 0 : v.integers[i], 0);
    }
    return;
  }
  if (quantised)
    put_number(w, chain, stream, v.number, k.resolution);
  else
    put_scalar(w, k.scalar, v.number, v.integer, v.count);
  if (k.aggregation == Aggregation::Average) w.varint(v.count);
}

void get_scalar(ByteReader& r, ScalarKind k, double& number, int64_t& integer, uint64_t& count) {
  switch (k) {
    case ScalarKind::F32: number = r.fixed<float>(); break;
    case ScalarKind::F64: number = r.fixed<double>(); break;
    case ScalarKind::ZigZag: integer = r.svarint(); break;
    case ScalarKind::Bool: {
      uint8_t b = r.u8();
      if (b > 1) r.fail("bool value not 0 or 1");
      integer = b;
      break;
    }
    case ScalarKind::UVarint: count = r.varint(); break;
  }
}

Value get_value(ByteReader& r, const ValueKind& k, Chain& chain, uint32_t stream) {
  if (is_event(k.aggregation)) return get_events(r, k);
  Value v;
  v.present = true;
  bool quantised = k.resolution > 0;
  if (k.aggregation == Aggregation::All) {
    uint64_t n = r.varint();
    if (n > r.remaining()) r.fail("ALL count exceeds frame");
    bool is_float = k.scalar == ScalarKind::F32 || k.scalar == ScalarKind::F64;
    for (uint64_t i = 0; i < n; ++i) {
      double d = 0;
      int64_t x = 0;
      uint64_t c = 0;
      if (quantised)
        d = get_number(r, chain, stream, k.resolution);
      else
        get_scalar(r, k.scalar, d, x, c);
      if (is_float)
        v.numbers.push_back(d);
      else
        v.integers.push_back(x);
    }
    v.count = n;
    return v;
  }
  if (quantised)
    v.number = get_number(r, chain, stream, k.resolution);
  else
    get_scalar(r, k.scalar, v.number, v.integer, v.count);
  if (k.aggregation == Aggregation::Average) v.count = r.varint();
  return v;
}

// The optional resolution field: count, then per declared stream its index gap and f64le step.
void put_resolutions(ByteWriter& w, const Config& c) {
  if (c.resolutions.empty()) return;
  if (!c.accepted_delay_ms || c.resolutions.size() != c.streams.size())
    throw Error(ErrorCode::Internal,
                "a CONFIG with resolutions needs the delay and one per stream");
  size_t n = 0;
  for (double x : c.resolutions) n += x > 0 ? 1 : 0;
  w.varint(n);
  int64_t last = -1;
  for (size_t i = 0; i < c.resolutions.size(); ++i) {
    if (!(c.resolutions[i] > 0)) continue;
    w.varint(static_cast<uint64_t>(static_cast<int64_t>(i) - last - 1));
    w.fixed<double>(c.resolutions[i]);
    last = static_cast<int64_t>(i);
  }
}

void get_resolutions(ByteReader& r, Config& c) {
  uint64_t n = r.varint();
  if (n < 1 || n > c.streams.size())
    r.fail("resolution count " + std::to_string(n) + " out of 1.." +
           std::to_string(c.streams.size()));
  c.resolutions.assign(c.streams.size(), 0);
  uint64_t i = UINT64_MAX;  // i + gap + 1 wraps to the first index
  for (uint64_t k = 0; k < n; ++k) {
    uint64_t gap = r.varint();
    if (gap >= c.streams.size())
      r.fail("resolution of a stream beyond the " + std::to_string(c.streams.size()));
    i += gap + 1;
    if (i >= c.streams.size())
      r.fail("resolution of stream " + std::to_string(i) + " of " +
             std::to_string(c.streams.size()));
    double x = r.fixed<double>();
    if (!(std::isfinite(x) && x > 0))
      r.fail("resolution of stream " + std::to_string(i) + " is not a positive number");
    c.resolutions[i] = x;
  }
}

}  // namespace

// ON_CHANGE: mode u8, deadband f64le; THRESHOLD: crossing u8, level and hysteresis f64le;
// then N (varint, 0: derived).
void put_event_params(ByteWriter& w, Aggregation a, const EventParams& e) {
  w.u8(e.code);
  if (a == Aggregation::OnChange) {
    w.fixed<double>(e.deadband);
  } else {
    w.fixed<double>(e.level);
    w.fixed<double>(e.hysteresis);
  }
  w.varint(e.max_events);
}

EventParams get_event_params(ByteReader& r, Aggregation a, const std::string& what) {
  EventParams e;
  e.code = r.u8();
  bool on_change = a == Aggregation::OnChange;
  if (on_change) {
    e.deadband = r.fixed<double>();
  } else {
    e.level = r.fixed<double>();
    e.hysteresis = r.fixed<double>();
  }
  uint64_t n = r.varint();
  bool code_ok = on_change ? e.code < events::kDeadbandModeCount : e.code >= 1 && e.code <= 3;
  bool numbers_ok = std::isfinite(e.deadband) && e.deadband >= 0 && std::isfinite(e.level) &&
                    std::isfinite(e.hysteresis) && e.hysteresis >= 0;
  if (!code_ok || !numbers_ok || n > events::kMaxEvents)
    r.fail(what + ": event parameters out of range");
  e.max_events = static_cast<uint32_t>(n);
  return e;
}

void encode_value(std::vector<uint8_t>& out, const ValueKind& k, const Value& v) {
  ByteWriter w(out);
  Chain chain;
  put_value(w, k, v, chain, 0);
}
Value decode_value(ByteReader& r, const ValueKind& k) {
  Chain chain;
  return get_value(r, k, chain, 0);
}

void encode_slot_values(std::vector<uint8_t>& out, std::span<const Value> values,
                        std::span<const ValueKind> kinds, std::span<const uint32_t> streams,
                        Chain& chain) {
  ByteWriter w(out);
  for (size_t i = 0; i < values.size(); ++i)
    if (values[i].present) put_value(w, kinds[i], values[i], chain, streams[i]);
}

Value decode_slot_value(ByteReader& r, const ValueKind& k, Chain& chain, uint32_t stream) {
  return get_value(r, k, chain, stream);
}

void write_sensor_health(ByteWriter& w, const std::vector<SensorHealth>& sensors) {
  w.varint(sensors.size());
  for (const auto& s : sensors) {
    w.string(s.name);
    w.varint(s.fields.size());
    for (uint64_t f : s.fields) w.varint(f);
  }
}

std::vector<SensorHealth> read_sensor_health(ByteReader& r) {
  uint64_t n = r.varint();
  if (n > kMaxHealthSensors)
    r.fail("more than " + std::to_string(kMaxHealthSensors) + " sensors' health");
  std::vector<SensorHealth> out(n);
  for (auto& s : out) {
    s.name = r.string(kMaxHealthName);
    if (s.name.empty()) r.fail("empty sensor name");
    uint64_t k = r.varint();
    if (k > kMaxHealthFields)
      r.fail("more than " + std::to_string(kMaxHealthFields) + " health fields");
    for (uint64_t i = 0; i < k; ++i) s.fields.push_back(r.varint());
  }
  return out;
}

void encode(std::vector<uint8_t>& out, const Message& m) {
  std::vector<uint8_t> body;
  ByteWriter w(body);
  MsgType type{};
  std::visit(
      [&](const auto& msg) {
        using T = std::decay_t<decltype(msg)>;
        if constexpr (std::is_same_v<T, Hello> || std::is_same_v<T, Challenge>) {
          type = std::is_same_v<T, Hello> ? MsgType::Hello : MsgType::Challenge;
          w.u8(msg.version);
          w.bytes(msg.nonce);
        } else if constexpr (std::is_same_v<T, Auth>) {
          type = MsgType::Auth;
          w.bytes(msg.mac);
        } else if constexpr (std::is_same_v<T, AuthOk>) {
          type = MsgType::AuthOk;
          w.bytes(msg.mac);
          w.u8(msg.config_id);
          w.fixed<uint64_t>(msg.epoch_ns);
        } else if constexpr (std::is_same_v<T, Ping> || std::is_same_v<T, Pong>) {
          type = std::is_same_v<T, Ping> ? MsgType::Ping : MsgType::Pong;
          w.bytes(msg.payload);
        } else if constexpr (std::is_same_v<T, Config>) {
          type = MsgType::Config;
          w.u8(msg.config_id);
          w.varint(msg.status_period_s);
          w.varint(msg.topics.size());
          for (const auto& t : msg.topics) {
            w.string(t.name);
            w.u8(static_cast<uint8_t>(t.type));
            w.varint(t.buffer_size);
            w.varint(t.period_us);
          }
          w.varint(msg.streams.size());
          for (const auto& s : msg.streams) {
            w.varint(s.topic);
            w.u8(static_cast<uint8_t>(s.aggregation));
            w.varint(s.period_us);
            if (s.aggregation == Aggregation::Percentile) w.fixed<double>(s.percentile);
            if (is_event(s.aggregation)) put_event_params(w, s.aggregation, s.event);
          }
          if (msg.accepted_delay_ms) w.varint(*msg.accepted_delay_ms);
          put_resolutions(w, msg);
        } else if constexpr (std::is_same_v<T, ConfigAck>) {
          type = MsgType::ConfigAck;
          w.u8(msg.config_id);
          w.u8(msg.status);
          w.fixed<uint64_t>(msg.epoch_ns);
        } else if constexpr (std::is_same_v<T, Onboard>) {
          type = MsgType::Onboard;
          if (msg.model.size() > kMaxOnboardWire)
            throw Error(ErrorCode::Internal, "ONBOARD above its wire limit");
          w.u8(msg.config_id);
          w.bytes(msg.model);
        } else if constexpr (std::is_same_v<T, OnboardAck>) {
          type = MsgType::OnboardAck;
          if (msg.answers.size() > kMaxOnboardWire)
            throw Error(ErrorCode::Internal, "ONBOARD_ACK above its wire limit");
          w.u8(msg.config_id);
          w.u8(msg.status);
          w.bytes(msg.answers);
        } else if constexpr (std::is_same_v<T, Status>) {
          type = MsgType::Status;
          w.varint(msg.counters.size());
          for (uint64_t c : msg.counters) w.varint(c);
          if (!msg.sensors.empty()) write_sensor_health(w, msg.sensors);
        } else if constexpr (std::is_same_v<T, ErrorMsg>) {
          type = MsgType::Error;
          w.u8(msg.code);
          w.string(msg.message);
        }
      },
      m);
  put_frame(out, type, body);
}

void encode_data(std::vector<uint8_t>& out, const Data& d, std::span<const ValueKind> kinds) {
  if (d.values.size() != kinds.size())
    throw Error(ErrorCode::Internal, "DATA has " + std::to_string(d.values.size()) +
                                         " values for " + std::to_string(kinds.size()) +
                                         " streams");
  bool all_present = true;
  for (const auto& v : d.values) all_present = all_present && v.present;
  std::vector<uint8_t> body;
  body.reserve(8 + d.values.size() * 5);
  ByteWriter w(body);
  if (d.sync) {
    w.u8(d.config_id);
    w.varint(d.slot);
  } else {
    w.u8(d.seq8);
  }
  if (!all_present) {
    size_t nbytes = (d.values.size() + 7) / 8;
    size_t at = body.size();
    body.resize(at + nbytes, 0);
    for (size_t i = 0; i < d.values.size(); ++i)
      if (d.values[i].present) body[at + i / 8] |= static_cast<uint8_t>(1u << (i % 8));
  }
  Chain chain;  // a DATA frame decodes on its own
  for (size_t i = 0; i < d.values.size(); ++i)
    if (d.values[i].present) put_value(w, kinds[i], d.values[i], chain, static_cast<uint32_t>(i));
  uint8_t type = static_cast<uint8_t>(MsgType::Data) | (all_present ? 0 : 1) | (d.sync ? 2 : 0);
  ByteWriter o(out);
  o.varint(body.size() + 1);
  o.u8(type);
  o.bytes(body);
}

std::optional<RawFrame> split_frame(std::span<const uint8_t> buf, size_t max_frame) {
  uint64_t len = 0;
  size_t i = 0;
  for (int shift = 0;; shift += 7) {
    if (i >= buf.size()) return std::nullopt;
    if (i >= 4) throw Error(ErrorCode::BadFrame, "frame length varint longer than 4 bytes", 0);
    uint8_t b = buf[i++];
    len |= static_cast<uint64_t>(b & 0x7F) << shift;
    if (!(b & 0x80)) break;
  }
  if (len == 0) throw Error(ErrorCode::BadFrame, "frame length 0", 0);
  if (len > max_frame)
    throw Error(ErrorCode::BadFrame,
                "frame length " + std::to_string(len) + " above limit " + std::to_string(max_frame),
                0);
  if (buf.size() - i < len) return std::nullopt;
  RawFrame f;
  f.type = buf[i];
  f.body = buf.subspan(i + 1, static_cast<size_t>(len) - 1);
  f.size = i + static_cast<size_t>(len);
  return f;
}

bool is_data_type(uint8_t type) { return type >= 0x10 && type <= 0x13; }

// ONBOARD's and ONBOARD_ACK's payload: the rest of the frame, bounded.
static std::vector<uint8_t> onboard_payload(ByteReader& r) {
  if (r.remaining() > kMaxOnboardWire)
    r.fail("on-board payload above " + std::to_string(kMaxOnboardWire) + " bytes");
  auto b = r.bytes(r.remaining());
  return {b.begin(), b.end()};
}

Message decode(const RawFrame& f) {
  ByteReader r(f.body, 0);
  auto done = [&](Message m) {
    r.expect_end();
    return m;
  };
  switch (static_cast<MsgType>(f.type)) {
    case MsgType::Hello:
    case MsgType::Challenge: {
      uint8_t version = r.u8();
      Nonce n;
      get_array(r, n);
      if (f.type == static_cast<uint8_t>(MsgType::Hello)) return done(Hello{version, n});
      return done(Challenge{version, n});
    }
    case MsgType::Auth: {
      Auth a;
      get_array(r, a.mac);
      return done(a);
    }
    case MsgType::AuthOk: {
      AuthOk a;
      get_array(r, a.mac);
      a.config_id = r.u8();
      a.epoch_ns = r.fixed<uint64_t>();
      return done(a);
    }
    case MsgType::Ping:
    case MsgType::Pong: {
      if (f.body.size() > kMaxPing) r.fail("PING/PONG payload above 64 bytes");
      std::vector<uint8_t> p(f.body.begin(), f.body.end());
      if (f.type == static_cast<uint8_t>(MsgType::Ping)) return Ping{p};
      return Pong{p};
    }
    case MsgType::Config: {
      Config c;
      c.config_id = r.u8();
      uint64_t sp = r.varint();
      if (sp > kMaxStatusPeriodS) r.fail("status period above one day");
      c.status_period_s = static_cast<uint32_t>(sp);
      uint64_t nt = r.varint();
      if (nt > kMaxList || nt > r.remaining())
        r.fail("topic count " + std::to_string(nt) + " too large");
      for (uint64_t i = 0; i < nt; ++i) {
        TopicSpec t;
        t.name = r.string(kMaxName);
        uint8_t ty = r.u8();
        if (ty >= kValueTypeCount) r.fail("unknown value type " + std::to_string(ty));
        t.type = static_cast<ValueType>(ty);
        uint64_t bs = r.varint();
        if (bs < 1 || bs > kMaxBufferSize)
          r.fail("buffer size " + std::to_string(bs) + " out of 1.." +
                 std::to_string(kMaxBufferSize));
        t.buffer_size = static_cast<uint32_t>(bs);
        t.period_us = r.varint();
        c.topics.push_back(std::move(t));
      }
      uint64_t ns = r.varint();
      if (ns > kMaxList || ns > r.remaining())
        r.fail("stream count " + std::to_string(ns) + " too large");
      for (uint64_t i = 0; i < ns; ++i) {
        StreamSpec s;
        uint64_t topic = r.varint();
        if (topic >= nt)
          r.fail("stream " + std::to_string(i) + " names topic " + std::to_string(topic) + " of " +
                 std::to_string(nt));
        s.topic = static_cast<uint32_t>(topic);
        uint8_t a = r.u8();
        if (a >= table::kAggregationCount) r.fail("unknown aggregation " + std::to_string(a));
        s.aggregation = static_cast<Aggregation>(a);
        s.period_us = r.varint();
        if (s.period_us == 0 || s.period_us > kMaxPeriodUs) r.fail("stream period out of range");
        if (s.aggregation == Aggregation::Percentile) {
          s.percentile = r.fixed<double>();
          if (!(s.percentile >= 0 && s.percentile <= 100))  // NaN too
            r.fail("stream " + std::to_string(i) + ": percentile out of 0..100");
        }
        if (is_event(s.aggregation))
          s.event = get_event_params(r, s.aggregation, "stream " + std::to_string(i));
        c.streams.push_back(s);
      }
      if (r.remaining() > 0) {
        uint64_t d = r.varint();
        if (d > kMaxAcceptedDelayMs) r.fail("accepted delay above one hour");
        c.accepted_delay_ms = static_cast<uint32_t>(d);
      }
      if (r.remaining() > 0) get_resolutions(r, c);
      return done(c);
    }
    case MsgType::ConfigAck: {
      ConfigAck a;
      a.config_id = r.u8();
      a.status = r.u8();
      a.epoch_ns = r.fixed<uint64_t>();
      return done(a);
    }
    case MsgType::Onboard: {
      Onboard o;
      o.config_id = r.u8();
      o.model = onboard_payload(r);
      return done(o);
    }
    case MsgType::OnboardAck: {
      OnboardAck a;
      a.config_id = r.u8();
      a.status = r.u8();
      a.answers = onboard_payload(r);
      return done(a);
    }
    case MsgType::Status: {
      Status s;
      uint64_t n = r.varint();
      if (n > r.remaining()) r.fail("counter count exceeds frame");
      for (uint64_t i = 0; i < n; ++i) s.counters.push_back(r.varint());
      if (r.remaining() > 0) s.sensors = read_sensor_health(r);
      return done(s);
    }
    case MsgType::Error: {
      ErrorMsg e;
      e.code = r.u8();
      e.message = r.string(1024);
      return done(e);
    }
    default: break;
  }
  throw Error(ErrorCode::BadFrame,
              "unknown message type 0x" + to_hex(std::span<const uint8_t>(&f.type, 1)), 0);
}

DataHeader decode_data_header(const RawFrame& f) {
  if (!is_data_type(f.type)) throw Error(ErrorCode::BadFrame, "not a DATA frame", 0);
  ByteReader r(f.body);
  DataHeader h;
  h.bitmap = f.type & 1;
  h.sync = f.type & 2;
  if (h.sync) {
    h.config_id = r.u8();
    h.slot = r.varint();
    h.seq8 = static_cast<uint8_t>(h.slot & 0xFF);
  } else {
    h.seq8 = r.u8();
  }
  h.values_offset = r.pos();
  return h;
}

Data decode_data(const RawFrame& f, std::span<const ValueKind> kinds) {
  DataHeader h = decode_data_header(f);
  ByteReader r(f.body.subspan(h.values_offset), h.values_offset);
  Data d;
  d.sync = h.sync;
  d.config_id = h.config_id;
  d.slot = h.slot;
  d.seq8 = h.seq8;
  d.values.resize(kinds.size());
  std::vector<bool> present(kinds.size(), true);
  if (h.bitmap) {
    auto bm = r.bytes((kinds.size() + 7) / 8);
    for (size_t i = 0; i < kinds.size(); ++i) present[i] = (bm[i / 8] >> (i % 8)) & 1;
    for (size_t i = kinds.size(); i < bm.size() * 8; ++i)
      if ((bm[i / 8] >> (i % 8)) & 1) r.fail("presence bit set beyond the slot's streams");
  }
  Chain chain;
  for (size_t i = 0; i < kinds.size(); ++i)
    if (present[i]) d.values[i] = get_value(r, kinds[i], chain, static_cast<uint32_t>(i));
  r.expect_end();
  return d;
}

}  // namespace modd::link
