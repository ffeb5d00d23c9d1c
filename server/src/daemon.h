#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "daemon_config.h"

#include "far/base/result.h"

namespace far::server {

/// Test seams of a Daemon; production code leaves them empty.
struct DaemonTestHooks {
  /// Runs on the LCM thread before each message is handled; may throw, to prove that a
  /// handler's exception is caught instead of ending the daemon.
  std::function<void(std::string_view channel)> before_message;
  /// The batcher's context is taken to fail (as on a driver that gives one context only), so
  /// that the daemon's fallback, each session issuing its own gpu steps, can be tested.
  bool batcher_context_fails = false;
};

/// far-daemon: serves many simulator sessions. Its parts:
///  - the socket server (socket_server.h) on its own thread: the local socket where clients
///    open sessions and ask for status, and where the daemon learns at once that a client is
///    gone;
///  - the message handlers (message_handlers.h) on the calling thread of Run: step requests
///    over LCM, authenticated and checked, queued per session;
///  - one worker per session (session_worker.h): its rings, scene updates, steps (on its own GL
///    context) and sealed replies.
/// Nothing a client sends reaches far/ unvalidated.
class Daemon {
 public:
  /// Connects LCM and takes the daemon's socket (its name). Errors: kInvalidArgument (config),
  /// kUnavailable (LCM; or another daemon of this name is running), kPermissionDenied (the
  /// socket directory is unsafe).
  static Result<std::unique_ptr<Daemon>> Create(const DaemonConfig& config,
                                                DaemonTestHooks hooks = {});
  ~Daemon();

  /// Serves until Stop (or `stop_flag` becomes true): first checks that a GL context can be
  /// made (kUnavailable, with what was tried, when none can), then serves. On stop it closes
  /// every session, telling its client, and returns once every worker has ended.
  Result<void> Run(const std::atomic<bool>* stop_flag = nullptr);
  /// Asks Run to finish (thread-safe).
  void Stop();

  /// GL_RENDERER once Run checked the context ("" before).
  std::string gl_renderer() const;

 private:
  struct Impl;
  explicit Daemon(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace far::server
