#pragma once

// far::client's way to the daemon: its local socket, found by name, tried with backoff while
// the daemon may still be starting; the open handshake (the segment arrives as a descriptor);
// the status request.

#include <sys/types.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "far/client/client.h"
#include "far/protocol/local_socket.h"
#include "far/protocol/message.h"
#include "far/protocol/shm_segment.h"

namespace far::client::internal {

/// The daemon's socket for these options: socket_path, else the default for the name.
std::string SocketPath(const ClientOptions& options);

/// The sockets of options.daemon in the socket directories after the first
/// (protocol::SocketDirectories), that exist: where Connect looks when the daemon at the first
/// cannot hear it. Empty when options.socket_path is given or $FAR_SOCKET_DIR is set.
std::vector<std::string> OtherSocketPaths(const ClientOptions& options);

/// What a daemon that opened a session but never answered its probe over LCM is told in
/// Connect's error: where it is, what was tried, and the likely cause. When the daemon's
/// network namespace can be read (/proc/<pid>/ns/net: a daemon of this user), the message says
/// whether it is another one than the client's; otherwise it names both likely causes (another
/// network namespace, another daemon serving this name).
struct NotHeard {
  std::string socket_path;
  pid_t daemon_pid = 0;
  std::string lcm_url;         ///< the URL the client used
  std::string daemon_lcm_url;  ///< the URL the daemon serves (its open reply)
  int probes = 0;
  std::chrono::milliseconds waited{0};
};
std::string NotHeardMessage(const ClientOptions& options, const NotHeard& what);

/// For ClientOptions::daemon "auto": `options` for each daemon auto may use, best first
/// (far::client::RankDaemons over FindDaemons, the job's GPUs and this process id), each with
/// its socket_path and name. Waits up to options.connect_timeout for a daemon to answer.
/// Errors: kUnavailable naming the directories looked in and what each socket said.
Result<std::vector<ClientOptions>> ChooseDaemons(const ClientOptions& options);

/// Connects to the daemon's socket, retrying (10 ms, doubling to 200 ms) while there is none
/// or it refuses, until options.connect_timeout. Errors: kUnavailable "no far-daemon named
/// 'far' is running (...)", kPermissionDenied (the socket fails the trust check).
Result<protocol::LocalConnection> ConnectToDaemon(const ClientOptions& options);

/// An accepted session: the daemon's reply and the mapped, checked segment.
struct OpenedSession {
  far_lcm::open_session_reply_t reply;
  std::unique_ptr<protocol::ShmSegment> segment;
};

/// Sends open_session_t on a fresh connection and waits for the reply and the segment while the
/// daemon is alive (it may still be making its GL context). Errors: the daemon's refusal,
/// kUnavailable (it went away), kTimeout, those of ShmSegment::Open.
Result<OpenedSession> OpenSession(protocol::LocalConnection& connection,
                                  const ClientOptions& options);

/// Sends status_request_t and returns the reply.
Result<DaemonStatus> RequestStatus(protocol::LocalConnection& connection,
                                   const ClientOptions& options);

}  // namespace far::client::internal
