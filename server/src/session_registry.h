#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "daemon_config.h"
#include "fair_scheduler.h"
#include "session.h"

#include "far/model/result.h"
#include "far/protocol/message_validate.h"

namespace far::server {

/// The open sessions and the queue of their steps: the state the LCM thread (opens, closes,
/// requests) and the GL thread (steps, freeing closed sessions) share. Thread-safe.
class SessionRegistry {
 public:
  explicit SessionRegistry(const DaemonConfig& config);

  /// Opens a session: checks the session limit and the ring sizes the client asked for,
  /// creates its shared-memory segment (with a fresh key) and registers it. Errors:
  /// kUnavailable (shutting down, shm failure), kLimitExceeded (max_sessions, ring sizes).
  Result<std::shared_ptr<Session>> Open(const protocol::OpenSessionParams& params);

  /// The open session with this id, or nullptr.
  std::shared_ptr<Session> Find(int64_t id) const;

  /// A closed session and the steps it still had queued (to be answered by the caller).
  struct Closed {
    std::shared_ptr<Session> session;
    std::deque<StepJob> pending;
  };
  /// Removes a session; the GL thread frees its pipeline and segment (WaitForWork).
  std::optional<Closed> Close(int64_t id);

  /// Queues a validated step. Errors: kBusy (queue or rate limits), kUnavailable (stopping).
  Result<void> Queue(StepJob job);

  /// What the GL thread does next.
  struct Work {
    std::optional<StepJob> job;                   ///< the next step, fairly chosen
    std::vector<std::shared_ptr<Session>> freed;  ///< closed sessions to free on the GL thread
    bool done = false;                            ///< stopping and nothing is left
  };
  /// GL thread: waits up to `timeout` for a step, a closed session or the stop.
  Work WaitForWork(std::chrono::milliseconds timeout);

  /// Every open session (a snapshot).
  std::vector<std::shared_ptr<Session>> Sessions() const;
  /// Ids of sessions whose client has been silent for more than `timeout_ms`.
  std::vector<int64_t> Silent(int64_t now_ms, int64_t timeout_ms) const;
  /// Shutdown: removes and returns every session.
  std::vector<std::shared_ptr<Session>> TakeAll();

  /// Stops taking sessions and steps; the queued steps are still handed out.
  void Stop();
  bool stopping() const { return stopping_; }
  size_t queued() const;

 private:
  const DaemonConfig& config_;
  mutable std::mutex mutex_;  // guards everything below
  std::condition_variable work_;
  std::map<int64_t, std::shared_ptr<Session>> sessions_;
  FairScheduler<StepJob> scheduler_;
  std::vector<std::shared_ptr<Session>> to_free_;
  int64_t next_session_id_ = 1;
  std::atomic<bool> stopping_{false};
};

}  // namespace far::server
