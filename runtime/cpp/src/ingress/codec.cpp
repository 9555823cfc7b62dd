#include "modd/ingress/codec.hpp"

#include "modd/util/bytes.hpp"

namespace modd::ingress {

using wire::put_frame;  // the framing the client writes too (modd/ingress/wire.hpp)

void encode_hello(std::vector<uint8_t>& out, const Hello& h) {
  std::vector<uint8_t> b;
  ByteWriter w(b);
  w.u8(h.version);
  w.string(h.publisher);
  put_frame(out, MsgType::Hello, b);
}

void encode_register(std::vector<uint8_t>& out, const Register& r) {
  std::vector<uint8_t> b;
  ByteWriter w(b);
  w.varint(r.local_id);
  w.u8(static_cast<uint8_t>(r.type));
  w.string(r.topic);
  put_frame(out, MsgType::Register, b);
}

void encode_samples(std::vector<uint8_t>& out, std::span<const Record> records,
                    const std::function<ValueType(uint32_t)>& type_of) {
  std::vector<uint8_t> b;
  b.reserve(2 + records.size() * 14);
  ByteWriter w(b);
  w.varint(records.size());
  for (const auto& r : records) {
    w.varint(r.local_id);
    w.fixed<int64_t>(r.timestamp_ns);
    switch (type_of(r.local_id)) {
      case ValueType::Float32: w.fixed<float>(static_cast<float>(r.number)); break;
      case ValueType::Float64: w.fixed<double>(r.number); break;
      case ValueType::Int: w.fixed<int64_t>(r.integer); break;
      case ValueType::Bool: w.u8(r.integer ? 1 : 0); break;
    }
  }
  put_frame(out, MsgType::Samples, b);
}

void encode_health(std::vector<uint8_t>& out, const std::vector<link::SensorHealth>& sensors) {
  std::vector<uint8_t> b;
  ByteWriter w(b);
  link::write_sensor_health(w, sensors);
  put_frame(out, MsgType::Health, b);
}

void encode_catalogue(std::vector<uint8_t>& out, const Catalogue& c) {
  std::vector<uint8_t> b;
  ByteWriter w(b);
  w.string(c.drone);
  w.varint(c.max_future_ms);
  w.varint(c.max_past_ms);
  w.u8(c.accept_unknown ? 1 : 0);
  w.varint(c.topics.size());
  for (const auto& t : c.topics) {
    w.u8(static_cast<uint8_t>(t.type));
    w.string(t.name);
  }
  put_frame(out, MsgType::Catalogue, b);
}

void encode_ack(std::vector<uint8_t>& out, const Ack& a) {
  std::vector<uint8_t> b;
  ByteWriter w(b);
  w.varint(a.received);
  w.varint(a.settled);
  w.varint(a.archived);
  put_frame(out, MsgType::Ack, b);
}

void encode_reject(std::vector<uint8_t>& out, const RejectMsg& r) {
  std::vector<uint8_t> b;
  ByteWriter w(b);
  w.varint(r.local_id);
  w.u8(r.reason);
  w.varint(r.count);
  w.string(r.detail.size() > kMaxName ? r.detail.substr(0, kMaxName) : r.detail);
  put_frame(out, MsgType::Reject, b);
}

void decode_reply(const RawFrame& f, ReplyHandler& h) {
  ByteReader r(f.body);
  switch (static_cast<MsgType>(f.type)) {
    case MsgType::Catalogue: {
      Catalogue c;
      c.drone = r.string(kMaxName);
      c.max_future_ms = r.varint();
      c.max_past_ms = r.varint();
      uint8_t u = r.u8();
      if (u > 1) r.fail("accept_unknown not 0 or 1");
      c.accept_unknown = u == 1;
      uint64_t n = r.varint();
      if (n > r.remaining() / 2) r.fail("topic count " + std::to_string(n) + " exceeds frame");
      for (uint64_t i = 0; i < n; ++i) {
        CatalogueTopic t;
        uint8_t ty = r.u8();
        if (ty >= link::kValueTypeCount) r.fail("unknown value type " + std::to_string(ty));
        t.type = static_cast<ValueType>(ty);
        t.name = r.string(kMaxName);
        if (t.name.empty()) r.fail("empty topic name");
        c.topics.push_back(std::move(t));
      }
      r.expect_end();
      h.on_catalogue(c);
      return;
    }
    case MsgType::Ack: {
      Ack a;
      a.received = r.varint();
      a.settled = r.varint();
      a.archived = r.varint();
      if (a.settled > a.received || a.archived > a.settled) r.fail("ACK counts out of order");
      r.expect_end();
      h.on_ack(a);
      return;
    }
    case MsgType::Reject: {
      RejectMsg m;
      uint64_t id = r.varint();
      if (id > kMaxLocalId) r.fail("local topic id above " + std::to_string(kMaxLocalId));
      m.local_id = static_cast<uint32_t>(id);
      m.reason = r.u8();
      m.count = r.varint();
      m.detail = r.string(kMaxName);
      r.expect_end();
      h.on_reject(m);
      return;
    }
    default: break;
  }
  throw Error(ErrorCode::BadFrame, "unknown ingress reply type " + std::to_string(f.type), 0);
}

void decode(const RawFrame& f, Handler& h, uint64_t* records_left) {
  ByteReader r(f.body);
  if (records_left) *records_left = 0;
  switch (static_cast<MsgType>(f.type)) {
    case MsgType::Hello: {
      Hello m;
      m.version = r.u8();
      if (m.version < kMinVersion || m.version > kVersion)
        r.fail("unsupported ingress version " + std::to_string(m.version));
      m.publisher = r.string(kMaxName);
      r.expect_end();
      h.on_hello(m);
      return;
    }
    case MsgType::Register: {
      Register m;
      uint64_t id = r.varint();
      if (id > kMaxLocalId) r.fail("local topic id above " + std::to_string(kMaxLocalId));
      m.local_id = static_cast<uint32_t>(id);
      uint8_t t = r.u8();
      if (t >= link::kValueTypeCount) r.fail("unknown value type " + std::to_string(t));
      m.type = static_cast<ValueType>(t);
      m.topic = r.string(kMaxName);
      if (m.topic.empty()) r.fail("empty topic name");
      r.expect_end();
      h.on_register(m);
      return;
    }
    case MsgType::Samples: {
      uint64_t n = r.varint();
      if (n > r.remaining() / 10) r.fail("record count " + std::to_string(n) + " exceeds frame");
      for (uint64_t i = 0; i < n; ++i) {
        if (records_left) *records_left = n - i;
        Record rec;
        uint64_t id = r.varint();
        ValueType t;
        if (id > kMaxLocalId || !h.type_of(static_cast<uint32_t>(id), t))
          r.fail("record " + std::to_string(i) + " uses unregistered local id " +
                 std::to_string(id));
        rec.local_id = static_cast<uint32_t>(id);
        rec.timestamp_ns = r.fixed<int64_t>();
        switch (t) {
          case ValueType::Float32: rec.number = r.fixed<float>(); break;
          case ValueType::Float64: rec.number = r.fixed<double>(); break;
          case ValueType::Int: rec.integer = r.fixed<int64_t>(); break;
          case ValueType::Bool: {
            uint8_t b = r.u8();
            if (b > 1) r.fail("bool value not 0 or 1");
            rec.integer = b;
            break;
          }
        }
        h.on_record(rec);
      }
      if (records_left) *records_left = 0;
      r.expect_end();
      return;
    }
    case MsgType::Health: {
      auto sensors = link::read_sensor_health(r);
      r.expect_end();
      h.on_health(std::move(sensors));
      return;
    }
    case MsgType::Catalogue:
    case MsgType::Ack:
    case MsgType::Reject: break;  // broker -> publisher only
  }
  throw Error(ErrorCode::BadFrame, "unknown ingress message type " + std::to_string(f.type), 0);
}

}  // namespace modd::ingress
