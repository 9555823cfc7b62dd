// The one error type of the C++ runtime: a code, a message, and where (a byte
// offset into a frame or a file) when that is known.
#pragma once
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "modd/util/error_code.gen.hpp"  // ErrorCode, the ERROR frame's codes (wire.json)

namespace modd {

const char* error_code_name(ErrorCode code);

class Error : public std::runtime_error {
 public:
  static constexpr size_t kNoOffset = static_cast<size_t>(-1);
  Error(ErrorCode code, const std::string& message, size_t offset = kNoOffset);
  ErrorCode code() const { return code_; }
  size_t offset() const { return offset_; }

 private:
  ErrorCode code_;
  size_t offset_;
};

}  // namespace modd
