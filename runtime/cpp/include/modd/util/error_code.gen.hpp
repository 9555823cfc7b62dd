// Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit.
// Wire enumerations, counts and limits (modd_contracts/wire.json).
#pragma once

#include <cstddef>
#include <cstdint>

// The code of an ERROR frame, and of the C++ runtime's one error type.
namespace modd {


// Why a frame or a session was refused.
enum class ErrorCode : uint8_t {
  BadFrame = 1,  // malformed bytes (truncated, overlong varint, bad type code)
  Version = 2,  // unsupported protocol version
  AuthFailed = 3,  // HMAC proof did not verify
  NotAuthenticated = 4,  // message other than the handshake before authentication
  BadConfig = 5,  // CONFIG (or config file) inconsistent
  Busy = 6,  // a CONFIG is already waiting for its switch date
  Timeout = 8,  // handshake or peer timeout
  Internal = 9,  // system call failure and the like
  Io = 10,  // file or socket error
};
// The number of ErrorCode values.
inline constexpr size_t kErrorCodeCount = 9;

}  // namespace modd
