#pragma once

// The daemon's local socket: an AF_UNIX SOCK_SEQPACKET socket (one message per datagram, in
// order, reliable) at <dir>/<name>.sock (channels.h). A client opens a session on it (the
// session's segment comes back as a file descriptor, SCM_RIGHTS) and keeps the connection
// for the life of the session, so each side learns at once when the other is gone; status
// requests use it too. The kernel tells the daemon which user each client is (SO_PEERCRED):
// the per-user limits rest on that, not on anything the client says. The client checks the
// daemon the same way (CheckDaemonSocket): nobody else can put a socket where it looks.

#include <sys/types.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "far/base/result.h"

namespace far::protocol {

/// Who is at the other end of a connection, as the kernel saw it at connect time.
struct PeerCredentials {
  pid_t pid = 0;
  uid_t uid = 0;
  gid_t gid = 0;
};

/// One message received on a connection, and the descriptor it carried (-1: none).
struct LocalMessage {
  std::vector<uint8_t> bytes;
  int fd = -1;  ///< owned by the receiver (close it)
};

/// One end of a connection (owns the descriptor). Move-only.
class LocalConnection {
 public:
  /// Client: connects to the daemon socket at `path`, then checks it (CheckDaemonSocket).
  /// Errors: kNotFound (no socket there: no daemon of that name), kUnavailable (refused: a
  /// daemon that died), kPermissionDenied (the socket fails the trust check), kInvalidArgument
  /// (the path is too long for a socket).
  static Result<LocalConnection> Connect(const std::string& path);

  explicit LocalConnection(int fd);
  LocalConnection(LocalConnection&& other) noexcept;
  LocalConnection& operator=(LocalConnection&& other) noexcept;
  ~LocalConnection();
  LocalConnection(const LocalConnection&) = delete;
  LocalConnection& operator=(const LocalConnection&) = delete;

  int fd() const { return fd_; }
  PeerCredentials peer() const;

  /// Sends one message and, when `fd_to_pass` >= 0, a copy of that descriptor. Never blocks
  /// for long: kBusy when the peer does not read. Errors: kUnavailable (the peer is gone).
  Result<void> Send(std::span<const uint8_t> bytes, int fd_to_pass = -1);
  /// Receives one message of at most `max_bytes`, waiting up to `timeout`. A descriptor comes
  /// back only when `accept_fd`; any other one the peer sent is closed at once. Errors:
  /// kTimeout, kUnavailable (the peer closed the connection), kLimitExceeded (the message was
  /// larger than max_bytes; it is discarded).
  Result<LocalMessage> Receive(size_t max_bytes, std::chrono::milliseconds timeout,
                               bool accept_fd = false);
  /// True when the peer has closed its end (or the connection failed); never blocks.
  bool PeerClosed() const;

 private:
  int fd_ = -1;
};

/// The daemon's listening socket. Removes the socket file when destroyed.
class LocalListener {
 public:
  /// Makes the directory (mode 0755) when it is missing, refuses a directory that others may
  /// write to, removes a stale socket left by a dead daemon, binds `path` and lets every local
  /// user connect (mode 0666). Errors: kUnavailable (another daemon listens there: its name is
  /// taken; or socket/bind/listen failed), kPermissionDenied (the directory is unsafe),
  /// kInvalidArgument (path too long).
  static Result<std::unique_ptr<LocalListener>> Listen(const std::string& path);
  ~LocalListener();
  LocalListener(const LocalListener&) = delete;
  LocalListener& operator=(const LocalListener&) = delete;

  int fd() const { return fd_; }
  const std::string& path() const { return path_; }
  /// Accepts a pending connection without blocking; nullopt when none is pending, or when
  /// the process is out of descriptors (EMFILE, ENFILE): then out_of_descriptors() is true
  /// and one pending connection was closed unanswered, with a descriptor kept in reserve for
  /// this (its client hears at once that the connection closed, instead of waiting in the
  /// backlog, and the listener does not stay readable for a connection that cannot be taken).
  std::optional<LocalConnection> Accept();
  /// Whether the last Accept found the process out of descriptors.
  bool out_of_descriptors() const { return out_of_descriptors_; }

 private:
  LocalListener() = default;
  // Closes the reserve descriptor, accepts one connection and closes it, then takes the
  // reserve again.
  void ShedOneConnection();
  int fd_ = -1;
  int reserve_fd_ = -1;  // /dev/null, kept for ShedOneConnection
  bool out_of_descriptors_ = false;
  std::string path_;
};

/// Client: may this socket be trusted as a far-daemon? The socket file must be owned by the
/// process that listens on it (`daemon`); its directory must not be writable by group or
/// others and belong to root, to this user or to the daemon's user; and when it belongs to
/// the daemon's user (a service account), its parent must belong to root and not be writable
/// by others (as /run/far in /run). So no other user can put a socket where a client looks
/// (a squatted /tmp/far-<uid> fails). Errors: kPermissionDenied naming what failed.
Result<void> CheckDaemonSocket(const std::string& path, const PeerCredentials& daemon);

}  // namespace far::protocol
