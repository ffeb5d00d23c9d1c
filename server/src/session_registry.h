#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "daemon_config.h"
#include "session.h"

#include "far/base/result.h"
#include "far/model/scene_budget.h"
#include "far/protocol/local_socket.h"
#include "far/protocol/message_validate.h"

namespace far::server {

/// The open sessions: opened by the socket server, found by the LCM thread, closed by either
/// (the client went away, or the daemon ends the session). Closing a session cancels its running
/// step and wakes its worker, which frees the session's pipeline and segment on its own thread
/// and ends; ReapWorkers joins the ended threads. Thread-safe.
class SessionRegistry {
 public:
  /// Sessions are admitted into `budget` (which must outlive this) as holders of their user,
  /// by the session's id, and leave it when their workers have ended.
  SessionRegistry(const DaemonConfig& config, SharedSceneBudget& budget)
      : config_(config), budget_(budget) {}

  /// Opens a session for a client of user `peer.uid`: checks this user's session limit and
  /// the ring sizes it asked for, admits the session and its segment's bytes into the shared
  /// budget (its user's fair share of max_sessions and max_segment_bytes_total: this may close
  /// sessions of users above their share, scene_budget.h), then creates its segment (with a
  /// fresh key) and registers it. Its worker is not started yet (the caller does, once the
  /// client has the segment). Errors: kUnavailable (shutting down, no memory for the segment),
  /// kLimitExceeded (the user's share, max_sessions_per_user, ring sizes).
  Result<std::shared_ptr<Session>> Open(const protocol::OpenSessionParams& params,
                                        const protocol::PeerCredentials& peer);

  /// The open session with this id, or nullptr.
  std::shared_ptr<Session> Find(int64_t id) const;
  /// Every open session (a snapshot).
  std::vector<std::shared_ptr<Session>> Sessions() const;
  size_t size() const;

  /// Removes a session, cancels its running step and tells its worker to end; the steps it
  /// still had queued are dropped. Returns it (nullptr when it was not open).
  std::shared_ptr<Session> Close(int64_t id);
  /// Shutdown: stops taking sessions and closes every one; returns them.
  std::vector<std::shared_ptr<Session>> CloseAll();

  /// Joins the worker threads of closed sessions that have ended (all of them, waiting, when
  /// `wait`), and gives back what they held in the shared budget. Returns how many were joined.
  int ReapWorkers(bool wait = false);

  /// The open sessions that have had no step queued, running or ending for `timeout` by `now`.
  std::vector<int64_t> IdleSessions(Clock::time_point now, Clock::duration timeout) const;

 private:
  const DaemonConfig& config_;
  SharedSceneBudget& budget_;
  mutable std::mutex mutex_;
  std::map<int64_t, std::shared_ptr<Session>> sessions_;
  std::vector<std::shared_ptr<Session>> closed_;  // workers not yet joined
  int64_t next_session_id_ = 1;
  bool stopping_ = false;
};

}  // namespace far::server
