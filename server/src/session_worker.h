#pragma once

#include <functional>
#include <memory>
#include <string>

#include "active_sessions.h"
#include "daemon_config.h"
#include "daemon_stats.h"
#include "replier.h"
#include "session.h"
#include "setup_allowance.h"

#include "far/gpu/compute_batcher.h"
#include "far/model/scene_budget.h"

namespace far::server {

/// What every session worker shares.
struct WorkerContext {
  const DaemonConfig& config;
  Replier& replier;
  DaemonStats& stats;
  SharedSceneBudget& budget;        ///< the budgets users share (SessionRegistry's)
  SetupAllowance& setup_allowance;  ///< per user, one-off work that does not make a step heavy
  bool use_gl = true;               ///< the daemon made a GL context at start-up
  /// Ends a session from its worker (the segment became unreadable), telling its client.
  std::function<void(int64_t session_id, const std::string& reason)> close_session;
  /// The sessions stepping now (the daemon's); null: each session counts on all cpu_cores.
  ActiveSessions* active = nullptr;
  /// Where the sessions' gpu steps go together (DaemonConfig::gpu_batch); null: each session's
  /// own context.
  ComputeBatcher* compute_batcher = nullptr;
};

/// Starts the thread that serves one session: it takes the session's queued steps one at a
/// time, drains its update ring, applies the updates (all or nothing, within the session's and
/// the daemon's budgets), runs the pipeline under the step's deadline and cancellation, and
/// publishes statuses and the reply. The session's pipeline (with its own GL context, made on
/// this thread) and segment live and die on this thread. A session whose steps take more than
/// heavy_step_ms is moved to a lower CPU priority, so that it cannot starve light ones. The
/// thread ends when the session is closed; SessionRegistry::ReapWorkers joins it. A session
/// closed before its worker starts gets none.
void StartSessionWorker(const std::shared_ptr<Session>& session, const WorkerContext& context);

}  // namespace far::server
