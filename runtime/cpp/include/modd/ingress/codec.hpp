// Encoder and decoder of ingress frames (same framing as the link: varint
// length, type byte, body).
#pragma once
#include <functional>
#include <span>
#include <vector>

#include "modd/ingress/messages.hpp"
#include "modd/link/codec.hpp"

namespace modd::ingress {

using link::RawFrame;
using link::split_frame;

void encode_hello(std::vector<uint8_t>& out, const Hello& h);
void encode_register(std::vector<uint8_t>& out, const Register& r);
// Records must use local ids whose types are given by type_of.
void encode_samples(std::vector<uint8_t>& out, std::span<const Record> records,
                    const std::function<ValueType(uint32_t)>& type_of);

// HEALTH: the publisher's instruments (modd-sensors), replacing what it said before.
void encode_health(std::vector<uint8_t>& out, const std::vector<link::SensorHealth>& sensors);

void encode_catalogue(std::vector<uint8_t>& out, const Catalogue& c);
void encode_ack(std::vector<uint8_t>& out, const Ack& a);
void encode_reject(std::vector<uint8_t>& out, const RejectMsg& r);

// The broker's answers, as a client decodes them.
class ReplyHandler {
 public:
  virtual ~ReplyHandler() = default;
  virtual void on_catalogue(const Catalogue& c) = 0;
  virtual void on_ack(const Ack& a) = 0;
  virtual void on_reject(const RejectMsg& r) = 0;
};
// Throws Error(BadFrame) with the offset.
void decode_reply(const RawFrame& f, ReplyHandler& h);

// Receives what a decoded frame carries.
class Handler {
 public:
  virtual ~Handler() = default;
  virtual void on_hello(const Hello& h) = 0;
  virtual void on_register(const Register& r) = 0;
  // Type of a registered local id, or false if the id was never registered.
  virtual bool type_of(uint32_t local_id, ValueType& out) const = 0;
  virtual void on_record(const Record& r) = 0;
  virtual void on_health(std::vector<link::SensorHealth>&& /*sensors*/) {}
};

// Decodes one frame and calls the handler. Throws Error(BadFrame) with the
// offset; records decoded before the error have been delivered already, and
// `records_left` tells how many the batch announced but did not deliver.
void decode(const RawFrame& f, Handler& h, uint64_t* records_left = nullptr);

}  // namespace modd::ingress
