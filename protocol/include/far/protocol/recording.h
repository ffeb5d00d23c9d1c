#pragma once

// far recordings (docs/record-replay.md): one session's ring records, step requests and step
// replies in one LCM log file (lcm_log.h), so that `far-client replay` can run the session again
// against any daemon and compare the replies, and LCM's tools can read it. Events, in the order
// the client produced them:
//   FARREC_HEADER   recording_header_t  first and only once: versions, client, daemon, renderer
//   FARREC_RING     ring_record_t       each update ring record as written (sequence 1, 2, ...)
//   FARREC_REQUEST  step_request_t      each step request as sent, auth zeroed
//   FARREC_REPLY    step_reply_t        each step's full reply (never a stub), or for a step that
//                                       failed without one (timeout, session closed) an error
//                                       reply built by the client (MakeStepErrorReply)
// A reply may follow later records and requests (a client may send the next step first).
//
// Reading a recording treats it as untrusted input: every event is bounded, decoded with
// DecodeMessage and checked for meaning (ValidateStepRequest, ParseStepReply, ParseRingRecord)
// and for order (sequences 1, 2, ..., step ids increasing, a commit sequence only over records
// already seen, one reply per request) before replay sends anything.

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "far/base/result.h"
#include "far/model/mesh.h"
#include "far/model/pose.h"
#include "far/model/step_result.h"
#include "far/protocol/lcm_log.h"
#include "far/protocol/message.h"
#include "far/protocol/message_validate.h"
#include "far/protocol/ring_records.h"

namespace far::protocol {

/// recording_header_t.format_version of the recordings this build writes and reads.
inline constexpr int32_t kRecordingFormatVersion = 1;

inline constexpr std::string_view kRecordingHeaderChannel = "FARREC_HEADER";
inline constexpr std::string_view kRecordingRingChannel = "FARREC_RING";
inline constexpr std::string_view kRecordingRequestChannel = "FARREC_REQUEST";
inline constexpr std::string_view kRecordingReplyChannel = "FARREC_REPLY";

/// Byte caps of the events by channel: a header is small, a ring record at most a ring.
inline constexpr size_t kMaxRecordingHeaderBytes = size_t{64} << 10;
inline constexpr size_t kMaxRingRecordEventBytes = size_t{1} << 30;  // kMaxRingCapacity
/// The largest event a recording may hold (the reader's limit).
inline constexpr size_t kMaxRecordingEventBytes = kMaxRingRecordEventBytes + 4096;

// ---- writing (the client library's recorder) -------------------------------------------------

/// A ring_record_t for one update record, as UpdateWriter wrote it: the same ids, counts, bits.
far_lcm::ring_record_t MakeAddObjectRingRecord(uint64_t sequence, int64_t step_id, uint32_t id,
                                               const Mesh& mesh, Motion motion, const Pose& X_WO);
far_lcm::ring_record_t MakeRemoveObjectRingRecord(uint64_t sequence, int64_t step_id, uint32_t id);
far_lcm::ring_record_t MakeSetPoseRingRecord(uint64_t sequence, int64_t step_id, uint32_t id,
                                             const Pose& X_WO);
far_lcm::ring_record_t MakeSetVerticesRingRecord(uint64_t sequence, int64_t step_id, uint32_t id,
                                                 std::span<const Eigen::Vector3d> p_MV);

// ---- reading (replay) ------------------------------------------------------------------------

/// A recorded ring record, checked and converted.
struct RecordedUpdate {
  uint64_t sequence = 0;
  int64_t step_id = 0;
  RingUpdate update;
};

/// Checks a decoded ring_record_t's structure: sequence >= 1, step_id >= 0, a known type, an
/// object id in [0, 2^32 - 1], for add_object a known motion and whole vertices and triangles
/// (counts multiples of 3, at least one each, at most 2^32 - 1), for set_vertices whole
/// vertices, and every field the type does not use zero or empty. Values (finite, unit
/// quaternions, indices in range) are left to the daemon, which checks them when replay writes
/// the record, as it checks every record. Errors: kParseError naming the field.
Result<RecordedUpdate> ParseRingRecord(const far_lcm::ring_record_t& record);

/// Writes a recorded update into a session's ring bit for bit (UpdateWriter).
Result<RecordPosition> WriteRecordedUpdate(UpdateWriter& writer, const RingUpdate& update,
                                           std::chrono::milliseconds timeout);

/// One recorded step: its checked request, the events of the ring records it commits, and its
/// reply's event (none when the client stopped before one came).
struct RecordedStep {
  StepCommand command;
  std::vector<uint64_t> ring_record_offsets;
  std::optional<uint64_t> reply_offset;
};

/// A recording's header and steps, after every event was read and checked.
struct RecordingIndex {
  far_lcm::recording_header_t header;
  std::vector<RecordedStep> steps;
  uint64_t ring_records = 0;         ///< ring records in the file
  uint64_t uncommitted_records = 0;  ///< written after the last step's commit (not replayed)
  int64_t events = 0;                ///< events in the file
};

/// Opens a recording for reading (LcmLogReader with kMaxRecordingEventBytes).
Result<std::unique_ptr<LcmLogReader>> OpenRecording(const std::string& path);

/// Reads and checks every event (see the top of this file). Errors name the event and what is
/// wrong: kParseError (not an LCM log, truncated, unknown channel, bad or misplaced event),
/// kVersionMismatch (another protocol or format version), kLimitExceeded (an event over its
/// channel's cap), kIoError.
Result<RecordingIndex> IndexRecording(LcmLogReader& log);

/// The ring record at `offset` (from RecordingIndex), decoded and checked.
Result<RecordedUpdate> ReadRecordedUpdate(LcmLogReader& log, uint64_t offset);

/// A recorded reply: the message, and its StepResult or the Error the step recorded (a failed
/// step is not a bad recording).
struct RecordedReply {
  far_lcm::step_reply_t message;
  Result<StepResult> result = MakeError(ErrorCode::kInternal, "unset");
};
/// The reply at `offset` (from RecordingIndex), decoded and checked. Errors: those of reading
/// and checking the event (kParseError, kIoError, ...).
Result<RecordedReply> ReadRecordedReply(LcmLogReader& log, uint64_t offset);

}  // namespace far::protocol
