#pragma once

// Small helpers shared by the mesh and scene readers and writers: whole-file reading and
// writing, strict number parsing, and little/big-endian scalar decoding.

#include <bit>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>

#include "far/base/limits.h"
#include "far/base/result.h"

namespace far::internal {

/// Reads the whole file at `path` into a string.
/// Returns kIoError naming the path when it cannot be opened or read.
Result<std::string> ReadFileBytes(const std::filesystem::path& path);

/// Writes `bytes` to `path`, replacing the file. Returns kIoError naming the path on failure.
Result<void> WriteFileBytes(const std::filesystem::path& path, std::string_view bytes);

/// The outcome of parsing a number token.
enum class NumberStatus { kOk, kGarbage, kOutOfRange };

/// Parses all of `token` as a decimal floating-point number (an optional leading '+' is
/// accepted; "inf" and "nan" parse, so callers check std::isfinite). Never reads past `token`.
NumberStatus ParseDouble(std::string_view token, double* value);

/// Parses all of `token` as a decimal integer (optional leading '+' or '-').
NumberStatus ParseInt64(std::string_view token, int64_t* value);

/// Parses all of `token` as a decimal unsigned integer (optional leading '+').
NumberStatus ParseUint64(std::string_view token, uint64_t* value);

/// Returns `text` cut to at most `max_chars` characters with "..." appended when cut, and
/// with control and non-ASCII bytes shown as '?', for quoting untrusted input in messages.
std::string Quote(std::string_view text, size_t max_chars = 40);

/// Returns the shortest decimal text that parses back to exactly `value`.
std::string FormatDouble(double value);

/// The byte order of a binary file.
enum class ByteOrder { kLittle, kBig };

/// Reads a trivially copyable scalar T from `bytes` (at least sizeof(T) readable) in `order`.
template <typename T>
T LoadScalar(const char* bytes, ByteOrder order) {
  unsigned char buffer[sizeof(T)];
  std::memcpy(buffer, bytes, sizeof(T));
  static_assert(std::endian::native == std::endian::little, "host must be little-endian");
  if (order == ByteOrder::kBig) {
    for (size_t i = 0; i < sizeof(T) / 2; ++i) {
      const unsigned char tmp = buffer[i];
      buffer[i] = buffer[sizeof(T) - 1 - i];
      buffer[sizeof(T) - 1 - i] = tmp;
    }
  }
  T value;
  std::memcpy(&value, buffer, sizeof(T));
  return value;
}

/// Appends the little-endian bytes of scalar `value` to `out`.
template <typename T>
void AppendLittleEndian(T value, std::string* out) {
  static_assert(std::endian::native == std::endian::little, "host must be little-endian");
  char buffer[sizeof(T)];
  std::memcpy(buffer, &value, sizeof(T));
  out->append(buffer, sizeof(T));
}

/// Splits off the next line of `text` starting at `*pos`: returns it without its "\n" or
/// "\r\n" and advances `*pos` past the line break. @pre *pos < text.size()
std::string_view NextLine(std::string_view text, size_t* pos);

/// Returns the next whitespace-separated token of `line` at or after `*pos` and advances `*pos`
/// past it; returns an empty view when the line has no more tokens.
std::string_view NextToken(std::string_view line, size_t* pos);

/// True when `c` separates tokens: space, tab, \r, \n, \v, \f.
inline bool IsSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

}  // namespace far::internal
