#pragma once

#include <atomic>
#include <memory>

#include "daemon_config.h"

#include "far/model/result.h"

namespace far::server {

/// far-daemon: serves many simulator sessions from one GL context.
///
/// Threads: the calling thread of Run handles LCM (open, close, heartbeats, status, step
/// requests -> the fair scheduler) and closes sessions that stopped sending heartbeats; one GL
/// thread owns the context and every session's pipeline, drains rings, runs steps (exact tests
/// on a CPU pool) and publishes replies. Nothing a client sends reaches far/ unvalidated.
class Daemon {
 public:
  /// Connects LCM and removes shared-memory segments left by dead daemons. The GL context is
  /// made by Run on its own thread. Errors: kUnavailable (LCM).
  static Result<std::unique_ptr<Daemon>> Create(const DaemonConfig& config);
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
