#pragma once

#include <functional>
#include <optional>
#include <span>
#include <string_view>
#include <utility>

#include "daemon_config.h"
#include "daemon_stats.h"
#include "replier.h"
#include "session_registry.h"

#include "far/protocol/lcm_bus.h"

namespace far::server {

/// The LCM side of the daemon: open, session (step, heartbeat, close) and status messages.
/// Everything a client sends is decoded, authenticated and validated here before it reaches a
/// session; nothing here runs a step. Handlers run on the LCM thread only.
class MessageHandlers {
 public:
  MessageHandlers(const DaemonConfig& config, SessionRegistry& sessions, Replier& replier,
                  DaemonStats& stats);

  /// Subscribes every handler on `bus`, each behind Guarded. `before_handle`, when set, runs
  /// before each handler (a test seam: it may throw).
  void Subscribe(protocol::LcmBus& bus,
                 std::function<void(std::string_view channel)> before_handle = {});

  /// Runs `handler` with the one catch of the daemon's dispatch: an exception is counted as
  /// "internal", logged in one line and, for a session channel, answered with an error_t;
  /// the daemon goes on serving.
  void Guarded(std::string_view channel, std::span<const uint8_t> bytes,
               const protocol::LcmBus::Handler& handler);

  /// Closes sessions whose client has been silent for heartbeat_timeout_ms.
  void ReapSilentSessions();
  /// Closes a session: its queued steps and (when `tell_client`) its client get an error.
  void CloseSession(int64_t id, const std::string& reason, bool tell_client);

  void OnOpen(std::string_view channel, std::span<const uint8_t> bytes);
  void OnSessionRequest(std::string_view channel, std::span<const uint8_t> bytes);
  void OnStatus(std::string_view channel, std::span<const uint8_t> bytes);

  /// GL_RENDERER for status replies (set once the GL thread made its context).
  void set_renderer(std::string renderer);

 private:
  template <typename T>
  std::optional<std::pair<T, std::shared_ptr<Session>>> AuthenticatedMessage(
      std::string_view channel, int64_t channel_session, std::span<const uint8_t> bytes);
  void OnStepRequest(std::string_view channel, int64_t channel_session,
                     std::span<const uint8_t> bytes);
  void OnHeartbeat(std::string_view channel, int64_t channel_session,
                   std::span<const uint8_t> bytes);
  bool AnswerOtherVersion(std::span<const uint8_t> bytes, const Error& error);

  const DaemonConfig& config_;
  SessionRegistry& sessions_;
  Replier& replier_;
  DaemonStats& stats_;
  std::mutex renderer_mutex_;
  std::string renderer_;
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
};

}  // namespace far::server
