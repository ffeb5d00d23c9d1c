#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "daemon_config.h"

#include "far/model/result.h"

namespace far::server {

/// Test seams of a Daemon; production code leaves them empty.
struct DaemonTestHooks {
  /// Runs on the LCM thread before each message is handled; may throw, to prove that a
  /// handler's exception becomes an error reply instead of ending the daemon.
  std::function<void(std::string_view channel)> before_message;
};

/// far-daemon: serves many simulator sessions from one GL context. Three parts:
///  - the session registry (session_registry.h): open sessions and their queued steps;
///  - the message handlers (message_handlers.h) on the calling thread of Run: LCM open,
///    session and status messages, each behind one try/catch, and the heartbeat reaper;
///  - the step runner (step_runner.h) on the GL thread: rings, scene updates, steps, replies.
/// Nothing a client sends reaches far/ unvalidated.
class Daemon {
 public:
  /// Connects LCM and removes shared-memory segments left by dead daemons. The GL context is
  /// made by Run on its own thread. Errors: kInvalidArgument (config), kUnavailable (LCM).
  static Result<std::unique_ptr<Daemon>> Create(const DaemonConfig& config,
                                                DaemonTestHooks hooks = {});
  ~Daemon();

  /// Serves until Stop (or `stop_flag` becomes true): makes the GL context (kUnavailable, with
  /// what was tried, when none can be made), then handles messages. On stop it stops taking
  /// steps, drains the queued ones, closes every session (their segments are removed) and
  /// returns.
  Result<void> Run(const std::atomic<bool>* stop_flag = nullptr);
  /// Asks Run to finish (thread-safe).
  void Stop();

  /// GL_RENDERER once Run made the context ("" before).
  std::string gl_renderer() const;

 private:
  struct Impl;
  explicit Daemon(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace far::server
