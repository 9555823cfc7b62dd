// Encoder and decoder of ingress frames (same framing as the link: varint
// length, type byte, body).
#pragma once
#include <functional>
#include <span>
#include <vector>

#include "modd/ingress/messages.hpp"
#include "modd/link/codec.hpp"

namespace modd::ingress {

void encode_hello(std::vector<uint8_t>& out, const Hello& h);
void encode_register(std::vector<uint8_t>& out, const Register& r);
// Records must use local ids whose types are given by type_of.
void encode_samples(std::vector<uint8_t>& out, std::span<const Record> records,
                    const std::function<ValueType(uint32_t)>& type_of);

// Receives what a decoded frame carries.
class Handler {
 public:
  virtual ~Handler() = default;
  virtual void on_hello(const Hello& h) = 0;
  virtual void on_register(const Register& r) = 0;
  // Type of a registered local id, or false if the id was never registered.
  virtual bool type_of(uint32_t local_id, ValueType& out) const = 0;
  virtual void on_record(const Record& r) = 0;
};

using link::RawFrame;
using link::split_frame;

// Decodes one frame and calls the handler. Throws Error(BadFrame) with the
// offset; records decoded before the error have been delivered already, and
// `records_left` tells how many the batch announced but did not deliver.
void decode(const RawFrame& f, Handler& h, uint64_t* records_left = nullptr);

}  // namespace modd::ingress
