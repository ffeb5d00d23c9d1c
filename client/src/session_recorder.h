#pragma once

// Recording a session (ClientOptions::record_path, FAR_RECORD; docs/record-replay.md): every
// update ring record the client writes, every step request it sends (auth zeroed) and every
// step's outcome go into one far recording (far/protocol/recording.h), an LCM log file.

#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "far/base/result.h"
#include "far/client/client.h"
#include "far/model/mesh.h"
#include "far/model/pose.h"
#include "far/protocol/convert.h"
#include "far/protocol/lcm_log.h"
#include "far/protocol/message.h"

namespace far::client::internal {

/// Thread safety: every method may be called from any thread (the user's writes and requests,
/// the receive thread's replies); events are written in the order the calls come.
class SessionRecorder {
 public:
  /// What the recording's header says about the session.
  struct Info {
    std::string client_name, daemon_name, gl_renderer;
    int64_t session_id = 0;
  };

  /// Creates the recording: `path` when no file has that name, else the first free
  /// "<stem>.<n><extension>" (n = 2, 3, ...; several sessions of one process or of several
  /// processes with the same FAR_RECORD each get a file, none is overwritten). The file is
  /// readable by its owner only. Errors: kIoError naming the path.
  static Result<std::unique_ptr<SessionRecorder>> Create(const std::string& path, const Info& info);

  void AddObject(uint64_t sequence, int64_t step_id, uint32_t id, const Mesh& mesh, Motion motion,
                 const Pose& X_WO);
  void RemoveObject(uint64_t sequence, int64_t step_id, uint32_t id);
  void SetPose(uint64_t sequence, int64_t step_id, uint32_t id, const Pose& X_WO);
  void SetVertices(uint64_t sequence, int64_t step_id, uint32_t id,
                   std::span<const Eigen::Vector3d> p_MV);
  /// A step request as sent; its auth is written as zeros.
  void Request(const far_lcm::step_request_t& request);
  /// A step's full reply, as the daemon sent it.
  void Reply(const far_lcm::step_reply_t& reply);
  /// A step that ended without a reply of its own (timeout, session closed, daemon error_t).
  void ErrorReply(const protocol::StepReplyIds& ids, const Error& error);

  /// The file actually written.
  const std::string& path() const { return path_; }

 private:
  SessionRecorder(std::unique_ptr<protocol::LcmLogWriter> log, std::string path)
      : log_(std::move(log)), path_(std::move(path)) {}
  template <typename T>
  void Write(std::string_view channel, const T& message, bool flush);

  std::mutex mutex_;
  std::unique_ptr<protocol::LcmLogWriter> log_;  // null once a write failed
  std::string path_;
};

/// The recorder for a new session: options.record_path, else FAR_RECORD; null when neither
/// names a file. Errors: those of SessionRecorder::Create.
Result<std::unique_ptr<SessionRecorder>> StartRecording(const ClientOptions& options,
                                                        int64_t session_id);

}  // namespace far::client::internal
