// Encoder and decoder of link frames: varint length, type byte, body.
// Every encode has its decode; decoders throw modd::Error(BadFrame) with the
// byte offset within the frame.
#pragma once
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "modd/link/messages.hpp"
#include "modd/link/quantise.hpp"
#include "modd/util/bytes.hpp"
#include "modd/util/error.hpp"

namespace modd::link {

// Appends one whole frame (length prefix included) to out.
void encode(std::vector<uint8_t>& out, const Message& m);
void encode_data(std::vector<uint8_t>& out, const Data& d, std::span<const ValueKind> kinds);

// A frame split from a byte stream: its type and body (after the type byte).
struct RawFrame {
  uint8_t type = 0;
  std::span<const uint8_t> body;
  size_t size = 0;  // whole frame size, length prefix included
};

// Splits the next frame from the front of buf. Returns nullopt if more bytes
// are needed; throws on a length of 0 or above kMaxFrame.
std::optional<RawFrame> split_frame(std::span<const uint8_t> buf, size_t max_frame = kMaxFrame);

bool is_data_type(uint8_t type);
Message decode(const RawFrame& f);  // any non-DATA frame

// DATA in two steps: the header tells which slot, the slot tells the kinds.
struct DataHeader {
  bool sync = false;
  bool bitmap = false;
  uint8_t config_id = 0;
  uint64_t slot = 0;
  uint8_t seq8 = 0;
  size_t values_offset = 0;  // offset in body where the bitmap/values start
};
DataHeader decode_data_header(const RawFrame& f);
Data decode_data(const RawFrame& f, std::span<const ValueKind> kinds);

// One value as DATA lays it out (table "Values"); shared with the backfill frames.
void encode_value(std::vector<uint8_t>& out, const ValueKind& k, const Value& v);
Value decode_value(ByteReader& r, const ValueKind& k);

// A slot's present values as a DATA datagram lays them out (values[i] of stream
// streams[i]); quantised ones against chain, the datagram's (updated).
void encode_slot_values(std::vector<uint8_t>& out, std::span<const Value> values,
                        std::span<const ValueKind> kinds, std::span<const uint32_t> streams,
                        Chain& chain);
Value decode_slot_value(ByteReader& r, const ValueKind& k, Chain& chain, uint32_t stream);

// An event stream's parameters after its period (CONFIG, BACKFILL_REQUEST): ON_CHANGE's
// mode u8 and deadband f64le, THRESHOLD's crossing u8, level and hysteresis f64le, then N
// (varint, 0: derived). The decoder checks them; `what` locates its error.
void put_event_params(ByteWriter& w, Aggregation a, const EventParams& e);
EventParams get_event_params(ByteReader& r, Aggregation a, const std::string& what);

// Instruments' health as STATUS and the ingress's HEALTH carry it: `count:varint` then
// `count` x { `name:string` `n:varint` `n` x `field:varint` } (bounds: kMaxHealth*).
void write_sensor_health(ByteWriter& w, const std::vector<SensorHealth>& sensors);
std::vector<SensorHealth> read_sensor_health(ByteReader& r);

}  // namespace modd::link
