#pragma once

#include <future>
#include <string>

#include "daemon_config.h"
#include "daemon_stats.h"
#include "message_handlers.h"
#include "replier.h"
#include "session_registry.h"

#include "far/model/result.h"

namespace far::server {

/// The GL thread: owns the one GL context and every session's pipeline. It takes queued steps
/// fairly from the registry, drains each session's update ring, applies the updates through
/// the session's scene model (all or nothing), runs the pipeline and publishes the reply; it
/// also frees closed sessions, on this thread because their pipelines hold GL objects.
class StepRunner {
 public:
  StepRunner(const DaemonConfig& config, SessionRegistry& sessions, MessageHandlers& handlers,
             Replier& replier, DaemonStats& stats)
      : config_(config),
        sessions_(sessions),
        handlers_(handlers),
        replier_(replier),
        stats_(stats) {}

  /// The thread's body: makes the context and reports GL_RENDERER (or why none could be made)
  /// through `ready`, then runs steps until the registry stops and nothing is queued; then
  /// closes every session, telling its client.
  void Run(std::promise<Result<std::string>> ready);

 private:
  void RunStep(StepJob& job);
  Result<void> Ingest(Session& session, const protocol::StepCommand& command);
  void ShutDown();

  const DaemonConfig& config_;
  SessionRegistry& sessions_;
  MessageHandlers& handlers_;
  Replier& replier_;
  DaemonStats& stats_;
};

}  // namespace far::server
