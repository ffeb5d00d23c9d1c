#pragma once

#include <string>
#include <utility>
#include <variant>

namespace far {

/// What went wrong, coarsely; the message of an Error says exactly what and where.
enum class ErrorCode {
  kInvalidArgument,   ///< a value is malformed or out of its domain (NaN, bad index, ...)
  kParseError,        ///< a file or message could not be parsed
  kIoError,           ///< a file could not be opened or read
  kNotFound,          ///< a named thing (object id, session, file) does not exist
  kLimitExceeded,     ///< a count or size is over a configured limit
  kUnavailable,       ///< a resource (GL context, daemon) cannot be reached or created
  kBusy,              ///< overloaded: try again later
  kPermissionDenied,  ///< wrong token or owner
  kTimeout,           ///< a bounded wait expired
  kVersionMismatch,   ///< protocol or layout version differs
  kInternal,          ///< our own bug, caught and reported instead of crashing
};

/// Returns a stable lower-case name for `code`, e.g. "invalid_argument".
const char* ToString(ErrorCode code);

/// An error code and a message that names the field or location and the bad value.
struct Error {
  ErrorCode code = ErrorCode::kInternal;
  std::string message;
};

/// Returns "code: message".
std::string ToString(const Error& error);

/// For messages that quote a value: the shortest text that reads back as the same double ("0.1",
/// "1e+13", "nan", "-inf").
std::string FormatDouble(double value);

/// The outcome of an operation on untrusted input: a value or an Error.
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : state_(std::move(value)) {}      // NOLINT(google-explicit-constructor)
  Result(Error error) : state_(std::move(error)) {}  // NOLINT(google-explicit-constructor)

  bool ok() const { return state_.index() == 0; }
  explicit operator bool() const { return ok(); }

  /// @pre ok()
  const T& value() const& { return std::get<0>(state_); }
  T& value() & { return std::get<0>(state_); }
  T&& value() && { return std::get<0>(std::move(state_)); }
  const T& operator*() const& { return value(); }
  T& operator*() & { return value(); }
  const T* operator->() const { return &value(); }
  T* operator->() { return &value(); }

  /// @pre !ok()
  const Error& error() const { return std::get<1>(state_); }

 private:
  std::variant<T, Error> state_;
};

/// The outcome of an operation with no value.
template <>
class [[nodiscard]] Result<void> {
 public:
  Result() = default;
  Result(Error error)
      : error_(std::move(error)), ok_(false) {}  // NOLINT(google-explicit-constructor)

  bool ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  /// @pre !ok()
  const Error& error() const { return error_; }

 private:
  Error error_;
  bool ok_ = true;
};

/// Shorthand for building an Error.
inline Error MakeError(ErrorCode code, std::string message) {
  return Error{code, std::move(message)};
}

}  // namespace far
