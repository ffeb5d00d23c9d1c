#include "session_recorder.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "far/model/version.h"
#include "far/protocol/recording.h"
#include "far/protocol/version.h"

namespace far::client::internal {
namespace {

// The recording's strings are bounded like everything a reader checks.
constexpr size_t kMaxHeaderString = 1024;

int64_t NowMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// "<stem>.<n><extension>" of `path` ("run.farrec" -> "run.2.farrec").
std::string NumberedPath(const std::string& path, int n) {
  const std::filesystem::path p(path);
  std::filesystem::path numbered = p.parent_path() / p.stem();
  numbered += "." + std::to_string(n) + p.extension().string();
  return numbered.string();
}

// Opens the first of path, <stem>.2<ext>, ... that does not exist yet (O_EXCL: two processes
// never get the same file).
Result<std::pair<int, std::string>> CreateFreshFile(const std::string& path) {
  constexpr int kMaxNumber = 9999;
  for (int n = 1; n <= kMaxNumber; ++n) {
    const std::string candidate = n == 1 ? path : NumberedPath(path, n);
    const int fd = open(candidate.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd >= 0) return std::pair{fd, candidate};
    if (errno != EEXIST) {
      return MakeError(ErrorCode::kIoError,
                       "cannot record to " + candidate + ": " + std::strerror(errno));
    }
  }
  return MakeError(ErrorCode::kIoError, "cannot record to " + path + ": it and " +
                                            NumberedPath(path, 2) + " .. " +
                                            NumberedPath(path, kMaxNumber) + " all exist");
}

}  // namespace

Result<std::unique_ptr<SessionRecorder>> SessionRecorder::Create(const std::string& path,
                                                                 const Info& info) {
  auto file = CreateFreshFile(path);
  if (!file) return file.error();
  auto log = protocol::LcmLogWriter::FromDescriptor(file->first, file->second);
  if (!log) return log.error();
  std::unique_ptr<SessionRecorder> recorder(new SessionRecorder(std::move(*log), file->second));
  far_lcm::recording_header_t header;
  header.protocol_version = protocol::kProtocolVersion;
  header.format_version = protocol::kRecordingFormatVersion;
  header.far_version = kVersion;
  header.client_name = info.client_name.substr(0, kMaxHeaderString);
  header.daemon_name = info.daemon_name.substr(0, kMaxHeaderString);
  header.gl_renderer = info.gl_renderer.substr(0, kMaxHeaderString);
  header.session_id = info.session_id;
  header.start_time_us = NowMicros();
  auto bytes = protocol::EncodeMessage(header);
  if (!bytes) return bytes.error();
  if (auto ok = recorder->log_->Write(protocol::kRecordingHeaderChannel, *bytes, NowMicros());
      !ok) {
    return ok.error();
  }
  if (auto ok = recorder->log_->Flush(); !ok) return ok.error();
  return recorder;
}

template <typename T>
void SessionRecorder::Write(std::string_view channel, const T& message, bool flush) {
  std::lock_guard lock(mutex_);
  if (!log_) return;
  auto bytes = protocol::EncodeMessage(message);
  Result<void> written = bytes ? log_->Write(channel, *bytes, NowMicros()) : bytes.error();
  if (written && flush) written = log_->Flush();
  if (!written) {
    // The session goes on; the recording stops here, and says so once.
    std::fprintf(stderr, "far::client: recording to %s stopped: %s\n", path_.c_str(),
                 ToString(written.error()).c_str());
    log_.reset();
  }
}

void SessionRecorder::AddObject(uint64_t sequence, int64_t step_id, uint32_t id, const Mesh& mesh,
                                Motion motion, const Pose& X_WO) {
  Write(protocol::kRecordingRingChannel,
        protocol::MakeAddObjectRingRecord(sequence, step_id, id, mesh, motion, X_WO), false);
}

void SessionRecorder::RemoveObject(uint64_t sequence, int64_t step_id, uint32_t id) {
  Write(protocol::kRecordingRingChannel,
        protocol::MakeRemoveObjectRingRecord(sequence, step_id, id), false);
}

void SessionRecorder::SetPose(uint64_t sequence, int64_t step_id, uint32_t id, const Pose& X_WO) {
  Write(protocol::kRecordingRingChannel,
        protocol::MakeSetPoseRingRecord(sequence, step_id, id, X_WO), false);
}

void SessionRecorder::SetVertices(uint64_t sequence, int64_t step_id, uint32_t id,
                                  std::span<const Eigen::Vector3d> p_MV) {
  Write(protocol::kRecordingRingChannel,
        protocol::MakeSetVerticesRingRecord(sequence, step_id, id, p_MV), false);
}

void SessionRecorder::Request(const far_lcm::step_request_t& request) {
  far_lcm::step_request_t unsigned_request = request;
  std::memset(unsigned_request.auth, 0, sizeof(unsigned_request.auth));
  Write(protocol::kRecordingRequestChannel, unsigned_request, false);
}

void SessionRecorder::Reply(const far_lcm::step_reply_t& reply) {
  Write(protocol::kRecordingReplyChannel, reply, true);
}

void SessionRecorder::ErrorReply(const protocol::StepReplyIds& ids, const Error& error) {
  Write(protocol::kRecordingReplyChannel, protocol::MakeStepErrorReply(ids, error), true);
}

}  // namespace far::client::internal
