// The one error type of the C++ runtime: a code, a message, and where (a byte
// offset into a frame or a file) when that is known.
#pragma once
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace modd {

enum class ErrorCode : uint8_t {
  BadFrame = 1,          // malformed bytes (truncated, overlong varint, bad type code)
  Version = 2,           // unsupported protocol version
  AuthFailed = 3,        // HMAC proof did not verify
  NotAuthenticated = 4,  // message other than the handshake before authentication
  BadConfig = 5,         // CONFIG (or config file) inconsistent
  Busy = 6,              // a CONFIG is already waiting for its switch date
  Timeout = 8,           // handshake or peer timeout
  Internal = 9,          // system call failure and the like
  Io = 10,               // file or socket error
};

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
