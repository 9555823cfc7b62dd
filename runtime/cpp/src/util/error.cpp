#include "modd/util/error.hpp"

namespace modd {

const char* error_code_name(ErrorCode code) {
  switch (code) {
    case ErrorCode::BadFrame: return "BAD_FRAME";
    case ErrorCode::Version: return "VERSION";
    case ErrorCode::AuthFailed: return "AUTH_FAILED";
    case ErrorCode::NotAuthenticated: return "NOT_AUTHENTICATED";
    case ErrorCode::BadConfig: return "BAD_CONFIG";
    case ErrorCode::Busy: return "BUSY";
    case ErrorCode::Timeout: return "TIMEOUT";
    case ErrorCode::Internal: return "INTERNAL";
    case ErrorCode::Io: return "IO";
  }
  return "UNKNOWN";
}

static std::string with_offset(ErrorCode code, const std::string& message, size_t offset) {
  std::string s = std::string(error_code_name(code)) + ": " + message;
  if (offset != Error::kNoOffset) s += " (at byte " + std::to_string(offset) + ")";
  return s;
}

Error::Error(ErrorCode code, const std::string& message, size_t offset)
    : std::runtime_error(with_offset(code, message, offset)), code_(code), offset_(offset) {}

}  // namespace modd
