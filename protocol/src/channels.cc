#include "far/protocol/channels.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>

namespace far::protocol {
namespace {

// Whether `path` is a directory of this user itself (not a symbolic link to one); else why not.
bool IsOwnDirectory(const std::string& path, std::string* why_not = nullptr) {
  struct stat info {};
  std::string why;
  if (lstat(path.c_str(), &info) != 0) {
    why = std::strerror(errno);
  } else if (S_ISLNK(info.st_mode)) {
    why = "is a symbolic link";
  } else if (!S_ISDIR(info.st_mode)) {
    why = "is not a directory";
  } else if (info.st_uid != geteuid()) {
    why = "belongs to uid " + std::to_string(info.st_uid);
  } else {
    return true;
  }
  if (why_not != nullptr) *why_not = path + " " + why;
  return false;
}

// The host name, with anything but [A-Za-z0-9.-] as '_' (it becomes part of a path).
std::string HostName() {
  char name[HOST_NAME_MAX + 1] = {};
  if (gethostname(name, sizeof(name) - 1) != 0 || name[0] == '\0') return "localhost";
  std::string host = name;
  for (char& c : host) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                       c == '.' || c == '-';
    if (!plain) c = '_';
  }
  return host;
}

// $HOME/.far/run-<host> when $HOME is a directory of this user, else "".
std::string HomeSocketDirectory() {
  const char* home = std::getenv("HOME");
  if (home == nullptr || *home != '/' || !IsOwnDirectory(home)) return "";
  return std::string(home) + "/.far/run-" + HostName();
}

}  // namespace

bool IsValidDaemonName(std::string_view name) {
  if (name.empty() || name.size() > 16 || name[0] < 'a' || name[0] > 'z') return false;
  for (const char c : name) {
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-')) return false;
  }
  return true;
}

std::string ChannelPrefix(std::string_view name) {
  if (name == kDefaultDaemonName) return "FAR_";
  std::string prefix = "FAR_";
  for (const char c : name) {
    if (c == '-') {
      prefix += '_';
    } else if (c >= 'a' && c <= 'z') {
      prefix += static_cast<char>(c - 'a' + 'A');
    } else {
      prefix += c;
    }
  }
  return prefix + "_";
}

std::string SessionRequestChannel(std::string_view prefix, int64_t session_id) {
  return std::string(prefix) + "S" + std::to_string(session_id) + "_REQ";
}

std::string SessionReplyChannel(std::string_view prefix, int64_t session_id) {
  return std::string(prefix) + "S" + std::to_string(session_id) + "_REPLY";
}

std::string SessionRequestChannelPattern(std::string_view prefix) {
  return std::string(prefix) + "S[0-9]+_REQ";
}

std::optional<int64_t> ParseSessionRequestChannel(std::string_view prefix,
                                                  std::string_view channel) {
  constexpr std::string_view kSuffix = "_REQ";
  if (channel.size() <= prefix.size() + 1 + kSuffix.size()) return std::nullopt;
  if (channel.substr(0, prefix.size()) != prefix || channel[prefix.size()] != 'S')
    return std::nullopt;
  if (channel.substr(channel.size() - kSuffix.size()) != kSuffix) return std::nullopt;
  const std::string_view digits =
      channel.substr(prefix.size() + 1, channel.size() - prefix.size() - 1 - kSuffix.size());
  // At most 18 digits: no overflow of int64; no leading zero: one name per session.
  if (digits.empty() || digits.size() > 18 || digits[0] == '0') return std::nullopt;
  int64_t id = 0;
  for (const char c : digits) {
    if (c < '0' || c > '9') return std::nullopt;
    id = id * 10 + (c - '0');
  }
  return id;
}

std::vector<std::string> SocketDirectories() {
  // Named by the user: that one alone.
  if (const char* dir = std::getenv("FAR_SOCKET_DIR"); dir != nullptr && *dir == '/') return {dir};
  std::vector<std::string> dirs;
  struct stat info {};
  if (stat("/run/far", &info) == 0 && S_ISDIR(info.st_mode)) dirs.emplace_back("/run/far");
  if (const char* runtime = std::getenv("XDG_RUNTIME_DIR"); runtime != nullptr && *runtime == '/')
    dirs.push_back(std::string(runtime) + "/far");
  dirs.push_back(PerUserSocketDirectory().path);
  return dirs;
}

UserSocketDirectory PerUserSocketDirectory() {
  UserSocketDirectory choice{"/tmp/far-" + std::to_string(geteuid()), ""};
  std::string why_not;
  if (IsOwnDirectory(choice.path, &why_not)) return choice;
  const std::string home = HomeSocketDirectory();
  struct stat info {};
  if (lstat(choice.path.c_str(), &info) != 0 && errno == ENOENT) {
    // Missing: the home directory stays in use once made (the other user may have removed
    // theirs since, and the daemon serves there still).
    if (!home.empty() && IsOwnDirectory(home)) choice.path = home;
    return choice;
  }
  // Someone else's, or a link: never this user's socket directory.
  choice.tmp_taken = why_not;
  if (!home.empty()) choice.path = home;
  return choice;
}

std::string DefaultSocketDirectory() { return SocketDirectories().front(); }

std::string DefaultSocketPath(std::string_view name) {
  return DefaultSocketDirectory() + "/" + std::string(name) + ".sock";
}

}  // namespace far::protocol
