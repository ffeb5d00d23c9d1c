#pragma once

#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "daemon_config.h"
#include "daemon_stats.h"
#include "rate_limiter.h"
#include "replier.h"
#include "session_registry.h"
#include "session_worker.h"
#include "status_reply.h"

#include "far/protocol/local_socket.h"

namespace far::server {

/// The daemon's local socket (protocol/local_socket.h) on a thread of its own: it accepts
/// connections, answers status requests, opens sessions (handing each client its segment) and
/// watches each session's connection, closing the session the moment its client goes away.
/// Per user (as the kernel reports it, SO_PEERCRED): at most max_sessions_per_user sessions,
/// max_opens_per_second_per_user opens, and MaxPendingPerUser() connections that have not said
/// what they want yet; a connection that says nothing within kHandshakeTimeout is dropped.
class SocketServer {
 public:
  static constexpr std::chrono::milliseconds kHandshakeTimeout{2000};
  /// How long the listener is not polled after an accept found the daemon out of file
  /// descriptors (it stays readable: polling it would spin).
  static constexpr std::chrono::milliseconds kOutOfDescriptorsPause{100};

  SocketServer(std::unique_ptr<protocol::LocalListener> listener, const DaemonConfig& config,
               SessionRegistry& sessions, DaemonStats& stats, const WorkerContext& workers,
               const StatusSources& status)
      : listener_(std::move(listener)),
        config_(config),
        sessions_(sessions),
        stats_(stats),
        workers_(workers),
        status_(status) {}

  /// Serves until `stop` is set. The sessions' connections close when the server is destroyed.
  void Run(const std::atomic<bool>& stop);

 private:
  struct Pending {
    protocol::LocalConnection connection;
    protocol::PeerCredentials peer;
    Clock::time_point deadline;
  };
  void AcceptAll();
  void Handshake(Pending& pending);
  void Open(Pending& pending, std::span<const uint8_t> bytes);
  void DropClosedSessions();
  int PendingOf(uid_t uid) const;
  // As many as the sessions a user may hold (at least 4, for status requests): clients of one
  // user started together all connect before the daemon hears from any of them, and each of
  // them must be heard (the cap was a fixed 4, and dropped the fifth of a burst unanswered).
  int MaxPendingPerUser() const;

  std::unique_ptr<protocol::LocalListener> listener_;
  const DaemonConfig& config_;
  SessionRegistry& sessions_;
  DaemonStats& stats_;
  const WorkerContext& workers_;
  const StatusSources& status_;
  std::vector<Pending> pending_;
  std::map<int64_t, protocol::LocalConnection> connections_;  // by session id
  std::map<uid_t, RateLimiter> open_rate_;
  Clock::time_point listener_paused_until_{};  // out of descriptors: see AcceptAll
};

}  // namespace far::server
