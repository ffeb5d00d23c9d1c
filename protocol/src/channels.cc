#include "far/protocol/channels.h"

namespace far::protocol {

std::string SessionRequestChannel(int64_t session_id) {
  return "FAR_S" + std::to_string(session_id) + "_REQ";
}

std::string SessionReplyChannel(int64_t session_id) {
  return "FAR_S" + std::to_string(session_id) + "_REPLY";
}

std::optional<int64_t> ParseSessionRequestChannel(std::string_view channel) {
  constexpr std::string_view kPrefix = "FAR_S";
  constexpr std::string_view kSuffix = "_REQ";
  if (channel.size() <= kPrefix.size() + kSuffix.size()) return std::nullopt;
  if (channel.substr(0, kPrefix.size()) != kPrefix) return std::nullopt;
  if (channel.substr(channel.size() - kSuffix.size()) != kSuffix) return std::nullopt;
  const std::string_view digits =
      channel.substr(kPrefix.size(), channel.size() - kPrefix.size() - kSuffix.size());
  // At most 18 digits: no overflow of int64; no leading zero: one name per session.
  if (digits.empty() || digits.size() > 18 || digits[0] == '0') return std::nullopt;
  int64_t id = 0;
  for (const char c : digits) {
    if (c < '0' || c > '9') return std::nullopt;
    id = id * 10 + (c - '0');
  }
  return id;
}

bool IsValidOpenReplyChannel(std::string_view channel) {
  if (channel.substr(0, kOpenReplyPrefix.size()) != kOpenReplyPrefix) return false;
  const std::string_view suffix = channel.substr(kOpenReplyPrefix.size());
  if (suffix.empty() || suffix.size() > 48) return false;
  for (const char c : suffix) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

}  // namespace far::protocol
