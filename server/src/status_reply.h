#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "daemon_config.h"
#include "daemon_stats.h"
#include "far_lcm/status_reply_t.hpp"
#include "session_registry.h"

#include "far/gpu/compute_batcher.h"
#include "far/model/scene_budget.h"

namespace far::server {

/// What a status reply is made of.
struct StatusSources {
  const DaemonConfig& config;
  const DaemonStats& stats;
  const SessionRegistry& sessions;
  const SharedSceneBudget& budget;  ///< the segment bytes in use
  std::string gl_renderer, gl_device;
  std::vector<std::string> gpu_names;  ///< what schedulers call its GPU (docs/cluster.md)
  std::chrono::steady_clock::time_point started;
  /// Where the sessions' gpu steps go together (DaemonConfig::gpu_batch); null: none.
  const ComputeBatcher* compute_batcher = nullptr;
};

/// The status for user `asker`: daemon-wide totals, and the sessions of that user only (every
/// session, with its user id, for root): another user's client names and scene sizes are
/// theirs.
far_lcm::status_reply_t MakeStatusReply(const StatusSources& sources, uid_t asker,
                                        int64_t request_id);

}  // namespace far::server
