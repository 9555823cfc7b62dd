#include "modd/ingress/codec.hpp"

#include "modd/util/bytes.hpp"

namespace modd::ingress {

namespace {
void frame(std::vector<uint8_t>& out, MsgType t, const std::vector<uint8_t>& body) {
  ByteWriter w(out);
  w.varint(body.size() + 1);
  w.u8(static_cast<uint8_t>(t));
  w.bytes(body);
}
}  // namespace

void encode_hello(std::vector<uint8_t>& out, const Hello& h) {
  std::vector<uint8_t> b;
  ByteWriter w(b);
  w.u8(h.version);
  w.string(h.publisher);
  frame(out, MsgType::Hello, b);
}

void encode_register(std::vector<uint8_t>& out, const Register& r) {
  std::vector<uint8_t> b;
  ByteWriter w(b);
  w.varint(r.local_id);
  w.u8(static_cast<uint8_t>(r.type));
  w.string(r.topic);
  frame(out, MsgType::Register, b);
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
  frame(out, MsgType::Samples, b);
}

void decode(const RawFrame& f, Handler& h, uint64_t* records_left) {
  ByteReader r(f.body);
  if (records_left) *records_left = 0;
  switch (static_cast<MsgType>(f.type)) {
    case MsgType::Hello: {
      Hello m;
      m.version = r.u8();
      if (m.version != kVersion) r.fail("unsupported ingress version " + std::to_string(m.version));
      m.publisher = r.string(255);
      r.expect_end();
      h.on_hello(m);
      return;
    }
    case MsgType::Register: {
      Register m;
      uint64_t id = r.varint();
      if (id > 65535) r.fail("local topic id above 65535");
      m.local_id = static_cast<uint32_t>(id);
      uint8_t t = r.u8();
      if (t > 3) r.fail("unknown value type " + std::to_string(t));
      m.type = static_cast<ValueType>(t);
      m.topic = r.string(255);
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
        if (id > 65535 || !h.type_of(static_cast<uint32_t>(id), t))
          r.fail("record " + std::to_string(i) + " uses unregistered local id " + std::to_string(id));
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
  }
  throw Error(ErrorCode::BadFrame, "unknown ingress message type " + std::to_string(f.type), 0);
}

}  // namespace modd::ingress
