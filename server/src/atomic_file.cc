#include "atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace far::server {
namespace {

Error IoError(const std::string& path, const std::string& what) {
  return MakeError(ErrorCode::kIoError, "'" + path + "': " + what + ": " + std::strerror(errno));
}

}  // namespace

Result<void> WriteFileAtomically(const std::string& path, const std::string& text) {
  const std::filesystem::path target(path);
  const std::filesystem::path directory =
      target.parent_path().empty() ? std::filesystem::path(".") : target.parent_path();
  std::string temp = (directory / ("." + target.filename().string() + ".XXXXXX")).string();
  const int fd = mkstemp(temp.data());
  if (fd < 0) return IoError(path, "cannot create a temporary file in " + directory.string());
  // Written whole, readable by all, then renamed over the old file.
  const char* data = text.data();
  size_t left = text.size();
  bool ok = true;
  std::string failed;
  while (ok && left > 0) {
    const ssize_t n = write(fd, data, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      ok = false;
      failed = "cannot write " + temp;
      break;
    }
    data += n;
    left -= static_cast<size_t>(n);
  }
  if (ok && fchmod(fd, 0644) != 0) {
    ok = false;
    failed = "cannot chmod " + temp;
  }
  const int saved_errno = errno;
  if (close(fd) != 0 && ok) {
    ok = false;
    failed = "cannot close " + temp;
  } else {
    errno = saved_errno;
  }
  if (ok && rename(temp.c_str(), path.c_str()) != 0) {
    ok = false;
    failed = "cannot rename " + temp + " over it";
  }
  if (ok) return {};
  Error error = IoError(path, failed);
  unlink(temp.c_str());
  return error;
}

}  // namespace far::server
