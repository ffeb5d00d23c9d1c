#pragma once

// What far-client's replay and Client::Connect need of a Client beyond its public interface.

#include <memory>

#include "session_recorder.h"

#include "far/client/client.h"
#include "far/protocol/ring_records.h"

namespace far::client::internal {

/// Replay writes recorded ring records into a session's update ring bit for bit (the public
/// calls normalize poses, which may change the last bit of a recorded quaternion).
struct ClientAccess {
  static protocol::UpdateWriter& Updates(Client& client);
};

/// The recorder for a new session: options.record_path, else FAR_RECORD; null when neither
/// names a file. Errors: those of SessionRecorder::Create.
Result<std::unique_ptr<SessionRecorder>> StartRecording(const ClientOptions& options,
                                                        int64_t session_id);

}  // namespace far::client::internal
