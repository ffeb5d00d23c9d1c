#include "far/protocol/recording.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include "pose_doubles.h"

#include "far/protocol/convert.h"

namespace far::protocol {
namespace {

namespace wire = far_lcm;

far_lcm::ring_record_t BaseRecord(uint64_t sequence, int64_t step_id, RecordType type,
                                  uint32_t id) {
  wire::ring_record_t record{};
  record.protocol_version = kProtocolVersion;
  record.sequence = static_cast<int64_t>(sequence);
  record.step_id = step_id;
  record.type = static_cast<int32_t>(type);
  record.object_id = id;
  record.num_coordinates = 0;
  record.num_indices = 0;
  return record;
}

void StorePositions(std::span<const Eigen::Vector3d> p_MV, wire::ring_record_t& record) {
  record.num_coordinates = static_cast<int32_t>(3 * p_MV.size());
  record.p_MV.resize(3 * p_MV.size());
  if (!p_MV.empty()) std::memcpy(record.p_MV.data(), p_MV.data(), p_MV.size_bytes());
}

Error Bad(const wire::ring_record_t& record, const std::string& field, const std::string& what) {
  return MakeError(
      ErrorCode::kParseError,
      "ring_record_t (sequence " + std::to_string(record.sequence) + ")." + field + ": " + what);
}

bool PoseIsZero(const double v[kPoseDoubles]) {
  for (int i = 0; i < kPoseDoubles; ++i) {
    if (v[i] != 0 || std::signbit(v[i])) return false;
  }
  return true;
}

// The vertices of `record`: a whole number of them, at least one.
Result<std::vector<Eigen::Vector3d>> LoadPositions(const wire::ring_record_t& record) {
  const int32_t n = record.num_coordinates;
  if (record.p_MV.size() != static_cast<size_t>(std::max(n, 0))) {
    return Bad(
        record, "p_MV",
        std::to_string(record.p_MV.size()) + " values for num_coordinates " + std::to_string(n));
  }
  if (n < 3 || n % 3 != 0) {
    return Bad(record, "num_coordinates", std::to_string(n) + " is not 3 * a vertex count >= 1");
  }
  std::vector<Eigen::Vector3d> positions(static_cast<size_t>(n / 3));
  std::memcpy(static_cast<void*>(positions.data()), record.p_MV.data(),
              static_cast<size_t>(n) * sizeof(double));
  return positions;
}

Result<RingUpdate> ParseAddObject(const wire::ring_record_t& record) {
  if (record.motion < 0 || record.motion > static_cast<int32_t>(WireMotion::kDeformable)) {
    return Bad(record, "motion",
               std::to_string(record.motion) + " is not 0 (static), 1 (rigid) or 2 (deformable)");
  }
  const int32_t n = record.num_indices;
  if (n < 3 || n % 3 != 0) {
    return Bad(record, "num_indices", std::to_string(n) + " is not 3 * a triangle count >= 1");
  }
  if (record.triangles.size() != static_cast<size_t>(n)) {
    return Bad(
        record, "triangles",
        std::to_string(record.triangles.size()) + " values for num_indices " + std::to_string(n));
  }
  auto positions = LoadPositions(record);
  if (!positions) return positions.error();
  far::AddObject add{static_cast<uint32_t>(record.object_id),
                     {},
                     static_cast<Motion>(record.motion),
                     internal::DecodePose(record.X_WO)};
  add.mesh.p_MV = std::move(*positions);
  add.mesh.triangles.resize(static_cast<size_t>(n / 3));
  // int32 bit patterns back to the uint32 indices the client wrote.
  static_assert(sizeof(TriangleIndices) == 3 * sizeof(int32_t));
  std::memcpy(static_cast<void*>(add.mesh.triangles.data()), record.triangles.data(),
              static_cast<size_t>(n) * sizeof(int32_t));
  return RingUpdate(std::move(add));
}

// Checks that the fields `type` does not use are zero or empty.
Result<void> CheckUnused(const wire::ring_record_t& record, bool uses_motion, bool uses_pose,
                         bool uses_vertices, bool uses_triangles) {
  if (!uses_motion && record.motion != 0) {
    return Bad(record, "motion", std::to_string(record.motion) + " is not 0 (unused)");
  }
  if (!uses_pose && !PoseIsZero(record.X_WO)) return Bad(record, "X_WO", "not zero (unused)");
  if (!uses_vertices && record.num_coordinates != 0) {
    return Bad(record, "num_coordinates",
               std::to_string(record.num_coordinates) + " is not 0 (unused)");
  }
  if (!uses_triangles && record.num_indices != 0) {
    return Bad(record, "num_indices", std::to_string(record.num_indices) + " is not 0 (unused)");
  }
  return {};
}

}  // namespace

// ---- writing ---------------------------------------------------------------------------------

wire::ring_record_t MakeAddObjectRingRecord(uint64_t sequence, int64_t step_id, uint32_t id,
                                            const Mesh& mesh, Motion motion, const Pose& X_WO) {
  wire::ring_record_t record = BaseRecord(sequence, step_id, RecordType::kAddObject, id);
  record.motion = static_cast<int32_t>(motion);
  internal::EncodePose(X_WO, record.X_WO);
  StorePositions(mesh.p_MV, record);
  record.num_indices = static_cast<int32_t>(3 * mesh.triangles.size());
  record.triangles.resize(3 * mesh.triangles.size());
  if (!mesh.triangles.empty()) {
    std::memcpy(record.triangles.data(), mesh.triangles.data(),
                mesh.triangles.size() * sizeof(TriangleIndices));
  }
  return record;
}

wire::ring_record_t MakeRemoveObjectRingRecord(uint64_t sequence, int64_t step_id, uint32_t id) {
  return BaseRecord(sequence, step_id, RecordType::kRemoveObject, id);
}

wire::ring_record_t MakeSetPoseRingRecord(uint64_t sequence, int64_t step_id, uint32_t id,
                                          const Pose& X_WO) {
  wire::ring_record_t record = BaseRecord(sequence, step_id, RecordType::kSetPose, id);
  internal::EncodePose(X_WO, record.X_WO);
  return record;
}

wire::ring_record_t MakeSetVerticesRingRecord(uint64_t sequence, int64_t step_id, uint32_t id,
                                              std::span<const Eigen::Vector3d> p_MV) {
  wire::ring_record_t record = BaseRecord(sequence, step_id, RecordType::kSetVertices, id);
  StorePositions(p_MV, record);
  return record;
}

// ---- one ring record -------------------------------------------------------------------------

Result<RecordedUpdate> ParseRingRecord(const wire::ring_record_t& record) {
  if (record.sequence < 1) {
    return Bad(record, "sequence", std::to_string(record.sequence) + " is not >= 1");
  }
  if (record.step_id < 0) {
    return Bad(record, "step_id", std::to_string(record.step_id) + " is negative");
  }
  if (record.object_id < 0 || record.object_id > int64_t{UINT32_MAX}) {
    return Bad(record, "object_id", std::to_string(record.object_id) + " is not a uint32");
  }
  const auto id = static_cast<uint32_t>(record.object_id);
  RecordedUpdate recorded{static_cast<uint64_t>(record.sequence), record.step_id, {}};
  switch (static_cast<RecordType>(record.type)) {
    case RecordType::kAddObject: {
      auto add = ParseAddObject(record);
      if (!add) return add.error();
      recorded.update = std::move(*add);
      return recorded;
    }
    case RecordType::kRemoveObject:
      if (auto ok = CheckUnused(record, false, false, false, false); !ok) return ok.error();
      recorded.update = far::RemoveObject{id};
      return recorded;
    case RecordType::kSetPose:
      if (auto ok = CheckUnused(record, false, true, false, false); !ok) return ok.error();
      recorded.update = far::SetPose{id, internal::DecodePose(record.X_WO)};
      return recorded;
    case RecordType::kSetVertices: {
      if (auto ok = CheckUnused(record, false, false, true, false); !ok) return ok.error();
      auto positions = LoadPositions(record);
      if (!positions) return positions.error();
      recorded.update = far::SetVertices{id, std::move(*positions)};
      return recorded;
    }
    case RecordType::kStepReply:
      break;
  }
  return Bad(record, "type",
             std::to_string(record.type) +
                 " is not 1 (add_object), 2 (remove_object), 3 (set_pose) or 4 (set_vertices)");
}

Result<RecordPosition> WriteRecordedUpdate(UpdateWriter& writer, const RingUpdate& update,
                                           std::chrono::milliseconds timeout) {
  struct Writer {
    UpdateWriter& w;
    std::chrono::milliseconds timeout;
    Result<RecordPosition> operator()(const far::AddObject& u) {
      return w.AddObject(u.id, u.mesh, u.motion, u.X_WO, timeout);
    }
    Result<RecordPosition> operator()(const far::RemoveObject& u) {
      return w.RemoveObject(u.id, timeout);
    }
    Result<RecordPosition> operator()(const far::SetPose& u) {
      return w.SetPose(u.id, u.X_WO, timeout);
    }
    Result<RecordPosition> operator()(const far::SetVertices& u) {
      return w.SetVertices(u.id, u.p_MV, timeout);
    }
  };
  return std::visit(Writer{writer, timeout}, update);
}

// ---- the whole file --------------------------------------------------------------------------

namespace {

std::string EventName(const LcmLogEvent& event) {
  return "event " + std::to_string(event.event_number) + " (byte " + std::to_string(event.offset) +
         ", " + event.channel + ")";
}

Error InEvent(const LcmLogEvent& event, const Error& error) {
  return MakeError(error.code, EventName(event) + ": " + error.message);
}

template <typename T>
Result<T> DecodeEvent(const LcmLogEvent& event, size_t cap) {
  auto message = DecodeMessage<T>(event.data.data(), event.data.size(), cap);
  if (!message) return InEvent(event, message.error());
  return message;
}

Result<RecordedUpdate> DecodeRingEvent(const LcmLogEvent& event) {
  auto record = DecodeEvent<wire::ring_record_t>(event, kMaxRingRecordEventBytes);
  if (!record) return record.error();
  auto parsed = ParseRingRecord(*record);
  if (!parsed) return InEvent(event, parsed.error());
  return parsed;
}

Result<RecordedReply> DecodeReplyEvent(const LcmLogEvent& event) {
  auto reply = DecodeEvent<wire::step_reply_t>(event, kMaxStepReplyBytes);
  if (!reply) return reply.error();
  if (reply->reply_in_shm) {
    return MakeError(ErrorCode::kParseError,
                     EventName(event) + ": step_reply_t.reply_in_shm: a stub, not a full reply");
  }
  RecordedReply recorded{std::move(*reply), MakeError(ErrorCode::kInternal, "unset")};
  recorded.result = ParseStepReply(recorded.message);
  // A failed step carries its error (status != 0); a successful one must parse.
  if (recorded.message.status == kWireOk && !recorded.result) {
    return InEvent(event, recorded.result.error());
  }
  return recorded;
}

// The checks of IndexRecording that need what came before.
class IndexBuilder {
 public:
  Result<void> Add(const LcmLogEvent& event) {
    if (event.channel == kRecordingHeaderChannel) return AddHeader(event);
    if (!have_header_) {
      return MakeError(ErrorCode::kParseError, EventName(event) +
                                                   ": the first event must be the FARREC_HEADER "
                                                   "recording_header_t (not a far recording?)");
    }
    if (event.channel == kRecordingRingChannel) return AddRing(event);
    if (event.channel == kRecordingRequestChannel) return AddRequest(event);
    if (event.channel == kRecordingReplyChannel) return AddReply(event);
    return MakeError(ErrorCode::kParseError,
                     EventName(event) + ": channel '" + event.channel +
                         "' is not FARREC_HEADER, FARREC_RING, FARREC_REQUEST or FARREC_REPLY");
  }

  Result<RecordingIndex> Finish() {
    if (!have_header_) {
      return MakeError(ErrorCode::kParseError,
                       "the file has no events (an empty or cut recording)");
    }
    const uint64_t committed =
        index_.steps.empty() ? 0 : index_.steps.back().command.ring_commit_sequence;
    index_.ring_records = ring_offsets_.size();
    index_.uncommitted_records = index_.ring_records - committed;
    return std::move(index_);
  }

 private:
  Result<void> AddHeader(const LcmLogEvent& event) {
    if (have_header_) {
      return MakeError(ErrorCode::kParseError, EventName(event) + ": a second header");
    }
    if (event.offset != 0) {
      return MakeError(ErrorCode::kParseError, EventName(event) + ": the header is not first");
    }
    // The format version first: a newer format may change what follows.
    auto header = DecodeMessageAnyVersion<wire::recording_header_t>(
        event.data.data(), event.data.size(), kMaxRecordingHeaderBytes);
    if (!header) return InEvent(event, header.error());
    if (header->format_version != kRecordingFormatVersion ||
        header->protocol_version != kProtocolVersion) {
      return MakeError(ErrorCode::kVersionMismatch,
                       EventName(event) + ": recording format " +
                           std::to_string(header->format_version) + ", protocol " +
                           std::to_string(header->protocol_version) + "; this build reads format " +
                           std::to_string(kRecordingFormatVersion) + ", protocol " +
                           std::to_string(kProtocolVersion));
    }
    index_.header = std::move(*header);
    have_header_ = true;
    return {};
  }

  Result<void> AddRing(const LcmLogEvent& event) {
    auto record = DecodeRingEvent(event);
    if (!record) return record.error();
    if (record->sequence != ring_offsets_.size() + 1) {
      return MakeError(ErrorCode::kParseError, EventName(event) + ": ring_record_t.sequence " +
                                                   std::to_string(record->sequence) +
                                                   " is not the next one (" +
                                                   std::to_string(ring_offsets_.size() + 1) + ")");
    }
    ring_offsets_.push_back(event.offset);
    return {};
  }

  Result<void> AddRequest(const LcmLogEvent& event) {
    auto message = DecodeEvent<wire::step_request_t>(event, kMaxControlMessageBytes);
    if (!message) return message.error();
    auto command = ValidateStepRequest(*message);
    if (!command) return InEvent(event, command.error());
    const uint64_t committed =
        index_.steps.empty() ? 0 : index_.steps.back().command.ring_commit_sequence;
    if (!index_.steps.empty() && command->step_id <= index_.steps.back().command.step_id) {
      return MakeError(ErrorCode::kParseError,
                       EventName(event) + ": step_request_t.step_id " +
                           std::to_string(command->step_id) + " is not after step " +
                           std::to_string(index_.steps.back().command.step_id));
    }
    if (command->ring_commit_sequence < committed ||
        command->ring_commit_sequence > ring_offsets_.size()) {
      return MakeError(ErrorCode::kParseError,
                       EventName(event) + ": step_request_t.ring_commit_sequence " +
                           std::to_string(command->ring_commit_sequence) + " is not in [" +
                           std::to_string(committed) + ", " + std::to_string(ring_offsets_.size()) +
                           "] (the records committed before and the records recorded)");
    }
    RecordedStep step;
    step.command = std::move(*command);
    step.ring_record_offsets.assign(
        ring_offsets_.begin() + static_cast<std::ptrdiff_t>(committed),
        ring_offsets_.begin() + static_cast<std::ptrdiff_t>(step.command.ring_commit_sequence));
    step_index_[step.command.step_id] = index_.steps.size();
    index_.steps.push_back(std::move(step));
    return {};
  }

  Result<void> AddReply(const LcmLogEvent& event) {
    auto reply = DecodeReplyEvent(event);
    if (!reply) return reply.error();
    const int64_t step_id = reply->message.step_id;
    auto it = step_index_.find(step_id);
    if (it == step_index_.end()) {
      return MakeError(ErrorCode::kParseError, EventName(event) + ": a reply to step " +
                                                   std::to_string(step_id) +
                                                   ", which no recorded request asked for");
    }
    RecordedStep& step = index_.steps[it->second];
    if (step.reply_offset) {
      return MakeError(ErrorCode::kParseError,
                       EventName(event) + ": a second reply to step " + std::to_string(step_id));
    }
    step.reply_offset = event.offset;
    return {};
  }

  RecordingIndex index_;
  bool have_header_ = false;
  std::vector<uint64_t> ring_offsets_;
  std::map<int64_t, size_t> step_index_;
};

}  // namespace

Result<std::unique_ptr<LcmLogReader>> OpenRecording(const std::string& path) {
  return LcmLogReader::Open(path, kMaxRecordingEventBytes);
}

Result<RecordingIndex> IndexRecording(LcmLogReader& log) {
  IndexBuilder builder;
  int64_t events = 0;
  for (;;) {
    auto event = log.Next();
    if (!event) return event.error();
    if (!event->has_value()) break;
    if (auto ok = builder.Add(**event); !ok) return ok.error();
    ++events;
  }
  auto index = builder.Finish();
  if (index) index->events = events;
  return index;
}

Result<RecordedUpdate> ReadRecordedUpdate(LcmLogReader& log, uint64_t offset) {
  auto event = log.ReadAt(offset);
  if (!event) return event.error();
  if (event->channel != kRecordingRingChannel) {
    return MakeError(ErrorCode::kParseError, EventName(*event) + ": not a FARREC_RING event");
  }
  return DecodeRingEvent(*event);
}

Result<RecordedReply> ReadRecordedReply(LcmLogReader& log, uint64_t offset) {
  auto event = log.ReadAt(offset);
  if (!event) return event.error();
  if (event->channel != kRecordingReplyChannel) {
    return MakeError(ErrorCode::kParseError, EventName(*event) + ": not a FARREC_REPLY event");
  }
  return DecodeReplyEvent(*event);
}

}  // namespace far::protocol
