#include "far/protocol/local_socket.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>

#include "errno_text.h"

namespace far::protocol {
namespace {

Result<sockaddr_un> AddressOf(const std::string& path) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof(address.sun_path)) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "socket path '" + path + "' is empty or longer than " +
                         std::to_string(sizeof(address.sun_path) - 1) + " bytes");
  }
  std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
  return address;
}

int NewSocket() { return socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0); }

// Closes every descriptor a received control message carried.
void CloseReceivedFds(msghdr& message, int* keep) {
  for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr; c = CMSG_NXTHDR(&message, c)) {
    if (c->cmsg_level != SOL_SOCKET || c->cmsg_type != SCM_RIGHTS) continue;
    const size_t count = (c->cmsg_len - CMSG_LEN(0)) / sizeof(int);
    for (size_t i = 0; i < count; ++i) {
      int fd;
      std::memcpy(&fd, CMSG_DATA(c) + i * sizeof(int), sizeof(int));
      if (keep != nullptr && *keep < 0) {
        *keep = fd;
      } else {
        close(fd);
      }
    }
  }
}

std::string Octal(mode_t mode) {
  char text[8];
  std::snprintf(text, sizeof(text), "%04o", static_cast<unsigned>(mode & 07777));
  return text;
}

// poll() that goes on waiting when a signal interrupts it (EINTR), for what is left of
// `timeout_ms` (>= 0): a signal meant for something else in the process (a timer, a child) is
// not the peer going away.
int PollRetrying(pollfd* fds, nfds_t count, int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  for (;;) {
    const int polled = poll(fds, count, timeout_ms);
    if (polled >= 0 || errno != EINTR) return polled;
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    timeout_ms = static_cast<int>(std::max<int64_t>(left.count(), 0));
  }
}

// A directory that group or others may write to (sticky or not) can hold anyone's socket.
bool WritableByOthers(const struct stat& info) { return (info.st_mode & (S_IWGRP | S_IWOTH)) != 0; }

}  // namespace

LocalConnection::LocalConnection(int fd) : fd_(fd) {}
LocalConnection::LocalConnection(LocalConnection&& other) noexcept : fd_(other.fd_) {
  other.fd_ = -1;
}
LocalConnection& LocalConnection::operator=(LocalConnection&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) close(fd_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}
LocalConnection::~LocalConnection() {
  if (fd_ >= 0) close(fd_);
}

Result<LocalConnection> LocalConnection::Connect(const std::string& path) {
  auto address = AddressOf(path);
  if (!address) return address.error();
  LocalConnection connection(NewSocket());
  if (connection.fd_ < 0) {
    return MakeError(ErrorCode::kUnavailable, "socket failed: " + ErrnoText(errno));
  }
  if (connect(connection.fd_, reinterpret_cast<const sockaddr*>(&*address), sizeof(*address)) !=
      0) {
    const int error = errno;
    if (error == ENOENT) {
      return MakeError(ErrorCode::kNotFound, "no far-daemon socket at " + path);
    }
    return MakeError(ErrorCode::kUnavailable,
                     "cannot connect to " + path + ": " + ErrnoText(error));
  }
  if (auto trusted = CheckDaemonSocket(path, connection.peer()); !trusted) return trusted.error();
  return connection;
}

PeerCredentials LocalConnection::peer() const {
  ucred credentials{};
  socklen_t size = sizeof(credentials);
  PeerCredentials peer;
  if (getsockopt(fd_, SOL_SOCKET, SO_PEERCRED, &credentials, &size) == 0) {
    peer.pid = credentials.pid;
    peer.uid = credentials.uid;
    peer.gid = credentials.gid;
  } else {
    peer.uid = static_cast<uid_t>(-1);  // unknown: matches nobody
    peer.gid = static_cast<gid_t>(-1);
  }
  return peer;
}

Result<void> LocalConnection::Send(std::span<const uint8_t> bytes, int fd_to_pass) {
  iovec io{const_cast<uint8_t*>(bytes.data()), bytes.size()};
  msghdr message{};
  message.msg_iov = &io;
  message.msg_iovlen = 1;
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int))] = {};
  if (fd_to_pass >= 0) {
    message.msg_control = control;
    message.msg_controllen = sizeof(control);
    cmsghdr* c = CMSG_FIRSTHDR(&message);
    c->cmsg_level = SOL_SOCKET;
    c->cmsg_type = SCM_RIGHTS;
    c->cmsg_len = CMSG_LEN(sizeof(int));
    std::memcpy(CMSG_DATA(c), &fd_to_pass, sizeof(int));
  }
  // A peer that does not read must not stall the sender: wait briefly, then give up.
  pollfd ready{fd_, POLLOUT, 0};
  if (PollRetrying(&ready, 1, 1000) <= 0 || (ready.revents & POLLOUT) == 0) {
    if (ready.revents & (POLLHUP | POLLERR)) {
      return MakeError(ErrorCode::kUnavailable, "the peer closed the connection");
    }
    return MakeError(ErrorCode::kBusy, "the peer does not read its socket");
  }
  const ssize_t sent = sendmsg(fd_, &message, MSG_NOSIGNAL | MSG_DONTWAIT);
  if (sent < 0) {
    const int error = errno;
    if (error == EAGAIN || error == EWOULDBLOCK)
      return MakeError(ErrorCode::kBusy, "the peer does not read its socket");
    return MakeError(ErrorCode::kUnavailable, "send failed: " + ErrnoText(error));
  }
  if (static_cast<size_t>(sent) != bytes.size()) {
    return MakeError(ErrorCode::kUnavailable, "send was cut short");
  }
  return {};
}

Result<LocalMessage> LocalConnection::Receive(size_t max_bytes, std::chrono::milliseconds timeout,
                                              bool accept_fd) {
  pollfd ready{fd_, POLLIN, 0};
  const int polled = PollRetrying(&ready, 1, static_cast<int>(timeout.count()));
  if (polled == 0) return MakeError(ErrorCode::kTimeout, "no message within the timeout");
  if (polled < 0) return MakeError(ErrorCode::kUnavailable, "poll failed: " + ErrnoText(errno));
  LocalMessage received;
  received.bytes.resize(max_bytes + 1);  // one more: a longer message shows as MSG_TRUNC
  iovec io{received.bytes.data(), received.bytes.size()};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int) * 4)] = {};
  msghdr message{};
  message.msg_iov = &io;
  message.msg_iovlen = 1;
  message.msg_control = control;
  message.msg_controllen = sizeof(control);
  const ssize_t got = recvmsg(fd_, &message, MSG_CMSG_CLOEXEC | MSG_DONTWAIT);
  if (got < 0) {
    const int error = errno;
    if (error == EAGAIN || error == EWOULDBLOCK)
      return MakeError(ErrorCode::kTimeout, "no message within the timeout");
    return MakeError(ErrorCode::kUnavailable, "receive failed: " + ErrnoText(error));
  }
  CloseReceivedFds(message, accept_fd ? &received.fd : nullptr);
  if (got == 0) {
    if (received.fd >= 0) close(received.fd);
    return MakeError(ErrorCode::kUnavailable, "the peer closed the connection");
  }
  if ((message.msg_flags & (MSG_TRUNC | MSG_CTRUNC)) != 0 || static_cast<size_t>(got) > max_bytes) {
    if (received.fd >= 0) close(received.fd);
    return MakeError(ErrorCode::kLimitExceeded,
                     "a message longer than " + std::to_string(max_bytes) + " bytes");
  }
  received.bytes.resize(static_cast<size_t>(got));
  return received;
}

bool LocalConnection::PeerClosed() const {
  pollfd ready{fd_, POLLRDHUP, 0};
  return PollRetrying(&ready, 1, 0) > 0 && (ready.revents & (POLLRDHUP | POLLHUP | POLLERR)) != 0;
}

Result<std::unique_ptr<LocalListener>> LocalListener::Listen(const std::string& path) {
  auto address = AddressOf(path);
  if (!address) return address.error();
  const std::filesystem::path directory = std::filesystem::path(path).parent_path();
  struct stat info {};
  if (stat(directory.c_str(), &info) != 0) {
    std::error_code ec;
    std::filesystem::create_directories(directory, ec);
    if (ec) {
      return MakeError(ErrorCode::kUnavailable, "cannot make the socket directory " +
                                                    directory.string() + ": " + ec.message());
    }
    chmod(directory.c_str(), 0755);
    if (stat(directory.c_str(), &info) != 0) {
      return MakeError(ErrorCode::kUnavailable, "cannot stat " + directory.string());
    }
  }
  if (!S_ISDIR(info.st_mode) || WritableByOthers(info) ||
      (info.st_uid != geteuid() && info.st_uid != 0)) {
    // Another user's: perhaps made to keep this daemon from starting (docs/daemon.md).
    const std::string whose =
        info.st_uid != geteuid() && info.st_uid != 0
            ? "; another user's directory: ask root to remove it, or listen elsewhere with "
              "--socket PATH (clients: --socket PATH or $FAR_SOCKET_DIR)"
            : "";
    return MakeError(ErrorCode::kPermissionDenied,
                     "socket directory " + directory.string() + " (owner uid " +
                         std::to_string(info.st_uid) + ", mode " + Octal(info.st_mode) +
                         ") must be a directory of this user or root that only its owner may "
                         "write to" +
                         whose);
  }
  // A socket already there: another daemon of this name, or one that died.
  if (lstat(path.c_str(), &info) == 0) {
    if (!S_ISSOCK(info.st_mode)) {
      return MakeError(ErrorCode::kUnavailable, path + " exists and is not a socket");
    }
    const int probe = NewSocket();
    const bool alive = probe >= 0 && connect(probe, reinterpret_cast<const sockaddr*>(&*address),
                                             sizeof(*address)) == 0;
    if (probe >= 0) close(probe);
    if (alive) {
      return MakeError(ErrorCode::kUnavailable,
                       "another far-daemon is listening on " + path +
                           " (its name is taken: start this one with another --name)");
    }
    unlink(path.c_str());
  }
  std::unique_ptr<LocalListener> listener(new LocalListener());
  listener->fd_ = NewSocket();
  if (listener->fd_ < 0) {
    return MakeError(ErrorCode::kUnavailable, "socket failed: " + ErrnoText(errno));
  }
  if (bind(listener->fd_, reinterpret_cast<const sockaddr*>(&*address), sizeof(*address)) != 0) {
    return MakeError(ErrorCode::kUnavailable, "bind(" + path + ") failed: " + ErrnoText(errno));
  }
  listener->path_ = path;
  // Any local user may ask for a session: the daemon's limits are per user.
  chmod(path.c_str(), 0666);
  if (listen(listener->fd_, 64) != 0) {
    return MakeError(ErrorCode::kUnavailable, "listen failed: " + ErrnoText(errno));
  }
  fcntl(listener->fd_, F_SETFL, fcntl(listener->fd_, F_GETFL) | O_NONBLOCK);
  listener->reserve_fd_ = open("/dev/null", O_RDONLY | O_CLOEXEC);
  return listener;
}

LocalListener::~LocalListener() {
  if (fd_ >= 0) close(fd_);
  if (reserve_fd_ >= 0) close(reserve_fd_);
  if (!path_.empty()) unlink(path_.c_str());
}

std::optional<LocalConnection> LocalListener::Accept() {
  const int fd = accept4(fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
  out_of_descriptors_ = fd < 0 && (errno == EMFILE || errno == ENFILE);
  if (out_of_descriptors_) ShedOneConnection();
  if (fd < 0) return std::nullopt;
  if (reserve_fd_ < 0) reserve_fd_ = open("/dev/null", O_RDONLY | O_CLOEXEC);
  return LocalConnection(fd);
}

void LocalListener::ShedOneConnection() {
  if (reserve_fd_ >= 0) close(reserve_fd_);
  const int fd = accept4(fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
  if (fd >= 0) close(fd);
  // Another thread may have taken the descriptor meanwhile: then there is no reserve until a
  // later Accept finds one free.
  reserve_fd_ = open("/dev/null", O_RDONLY | O_CLOEXEC);
}

Result<void> CheckDaemonSocket(const std::string& path, const PeerCredentials& daemon) {
  auto refuse = [&](const std::string& why) {
    return MakeError(ErrorCode::kPermissionDenied,
                     "not talking to the daemon socket " + path + ": " + why);
  };
  struct stat socket_info {};
  if (lstat(path.c_str(), &socket_info) != 0 || !S_ISSOCK(socket_info.st_mode))
    return refuse("it is not a socket");
  if (socket_info.st_uid != daemon.uid) {
    return refuse("the socket belongs to uid " + std::to_string(socket_info.st_uid) + " but uid " +
                  std::to_string(daemon.uid) + " listens on it");
  }
  const std::filesystem::path directory = std::filesystem::path(path).parent_path();
  struct stat dir_info {};
  if (stat(directory.c_str(), &dir_info) != 0) return refuse("its directory cannot be read");
  const uid_t me = geteuid();
  if (WritableByOthers(dir_info)) {
    return refuse("its directory " + directory.string() + " (mode " + Octal(dir_info.st_mode) +
                  ") may be written by other users");
  }
  const uid_t owner = dir_info.st_uid;
  if (owner == 0 || owner == me) return {};
  if (owner != daemon.uid) {
    return refuse("its directory belongs to uid " + std::to_string(owner) +
                  ", neither root, you, nor the daemon");
  }
  // A service account's directory: only root may have made it (as systemd makes /run/far).
  struct stat parent_info {};
  const std::filesystem::path parent = directory.parent_path();
  if (stat(parent.c_str(), &parent_info) != 0 || parent_info.st_uid != 0 ||
      WritableByOthers(parent_info)) {
    return refuse("its directory belongs to the daemon's user uid " + std::to_string(owner) +
                  " but sits in " + parent.string() + ", which root does not own alone");
  }
  return {};
}

}  // namespace far::protocol
