#include <charconv>

#include "far/base/result.h"

namespace far {

const char* ToString(ErrorCode code) {
  switch (code) {
    case ErrorCode::kInvalidArgument:
      return "invalid_argument";
    case ErrorCode::kParseError:
      return "parse_error";
    case ErrorCode::kIoError:
      return "io_error";
    case ErrorCode::kNotFound:
      return "not_found";
    case ErrorCode::kLimitExceeded:
      return "limit_exceeded";
    case ErrorCode::kUnavailable:
      return "unavailable";
    case ErrorCode::kBusy:
      return "busy";
    case ErrorCode::kPermissionDenied:
      return "permission_denied";
    case ErrorCode::kTimeout:
      return "timeout";
    case ErrorCode::kVersionMismatch:
      return "version_mismatch";
    case ErrorCode::kInternal:
      return "internal";
  }
  return "unknown";
}

std::string ToString(const Error& error) {
  return std::string(ToString(error.code)) + ": " + error.message;
}

std::string FormatDouble(double value) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof(text), value);
  return std::string(text, result.ptr);
}

}  // namespace far
