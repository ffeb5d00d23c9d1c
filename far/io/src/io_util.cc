#include "io_util.h"

#include <cerrno>
#include <charconv>
#include <fstream>
#include <iterator>
#include <system_error>

namespace far::internal {

Result<std::string> ReadFileBytes(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    return MakeError(ErrorCode::kIoError, path.string() + ": is a directory, not a file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    return MakeError(ErrorCode::kIoError,
                     path.string() + ": cannot open for reading: " +
                         std::make_error_code(static_cast<std::errc>(errno)).message());
  }
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return MakeError(ErrorCode::kIoError, path.string() + ": read failed");
  return bytes;
}

Result<void> WriteFileBytes(const std::filesystem::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) {
    return MakeError(ErrorCode::kIoError,
                     path.string() + ": cannot open for writing: " +
                         std::make_error_code(static_cast<std::errc>(errno)).message());
  }
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) return MakeError(ErrorCode::kIoError, path.string() + ": write failed");
  return {};
}

namespace {

// from_chars rejects a leading '+', which text formats allow; drop one (but not "+-1").
std::string_view StripPlus(std::string_view token) {
  if (token.size() >= 2 && token[0] == '+' && token[1] != '-' && token[1] != '+') {
    token.remove_prefix(1);
  }
  return token;
}

template <typename T>
NumberStatus ParseWhole(std::string_view token, T* value) {
  token = StripPlus(token);
  if (token.empty()) return NumberStatus::kGarbage;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, *value);
  if (ec == std::errc::result_out_of_range) return NumberStatus::kOutOfRange;
  if (ec != std::errc() || ptr != end) return NumberStatus::kGarbage;
  return NumberStatus::kOk;
}

}  // namespace

NumberStatus ParseDouble(std::string_view token, double* value) { return ParseWhole(token, value); }
NumberStatus ParseInt64(std::string_view token, int64_t* value) { return ParseWhole(token, value); }
NumberStatus ParseUint64(std::string_view token, uint64_t* value) {
  // from_chars for unsigned types accepts no sign at all; "-0" is garbage here, as it should be.
  return ParseWhole(token, value);
}

std::string Quote(std::string_view text, size_t max_chars) {
  std::string out = "'";
  for (size_t i = 0; i < text.size() && i < max_chars; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    out.push_back(c >= 0x20 && c < 0x7f ? static_cast<char>(c) : '?');
  }
  if (text.size() > max_chars) out += "...";
  out += "'";
  return out;
}

std::string FormatDouble(double value) {
  char buffer[64];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, ec == std::errc() ? ptr : buffer);
}

std::string_view NextLine(std::string_view text, size_t* pos) {
  const size_t begin = *pos;
  size_t end = text.find('\n', begin);
  if (end == std::string_view::npos) {
    end = text.size();
    *pos = text.size();
  } else {
    *pos = end + 1;
  }
  if (end > begin && text[end - 1] == '\r') --end;
  return text.substr(begin, end - begin);
}

std::string_view NextToken(std::string_view line, size_t* pos) {
  size_t begin = *pos;
  while (begin < line.size() && IsSpace(line[begin])) ++begin;
  size_t end = begin;
  while (end < line.size() && !IsSpace(line[end])) ++end;
  *pos = end;
  return line.substr(begin, end - begin);
}

}  // namespace far::internal
