#include "far/protocol/ring_records.h"

#include <cmath>
#include <cstddef>
#include <cstring>
#include <string>

#include "pose_doubles.h"

namespace far::protocol {
namespace {

static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double), "positions are copied as double[3V]");
static_assert(sizeof(TriangleIndices) == 3 * sizeof(uint32_t),
              "triangles are copied as uint32[3T]");

std::string RecordName(uint32_t type) {
  switch (static_cast<RecordType>(type)) {
    case RecordType::kAddObject:
      return "add_object";
    case RecordType::kRemoveObject:
      return "remove_object";
    case RecordType::kSetPose:
      return "set_pose";
    case RecordType::kSetVertices:
      return "set_vertices";
    case RecordType::kStepReply:
      return "step_reply";
  }
  return "type " + std::to_string(type);
}

// Builds errors that name the record, the field and the value.
class RecordErrors {
 public:
  explicit RecordErrors(const RecordHeader& header)
      : prefix_("update ring: record " + std::to_string(header.sequence) + " (" +
                RecordName(header.type) + "): ") {}
  Error Invalid(const std::string& field, const std::string& what) const {
    return MakeError(ErrorCode::kInvalidArgument, prefix_ + field + ": " + what);
  }
  Error Limit(const std::string& field, const std::string& what) const {
    return MakeError(ErrorCode::kLimitExceeded, prefix_ + field + ": " + what);
  }

 private:
  std::string prefix_;
};

template <typename T>
T Load(std::span<const uint8_t> bytes, size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;
}

Result<void> CheckSize(const RecordErrors& errors, uint32_t size, uint64_t expected,
                       const std::string& because) {
  if (size != expected) {
    return errors.Invalid("size", std::to_string(size) + " does not match " + because +
                                      " (expected " + std::to_string(expected) + ")");
  }
  return {};
}

Result<void> CheckCount(const RecordErrors& errors, const char* field, uint32_t count,
                        uint32_t limit) {
  if (count == 0) return errors.Invalid(field, "0 is not >= 1");
  if (count > limit) {
    return errors.Limit(field,
                        std::to_string(count) + " is over the limit " + std::to_string(limit));
  }
  return {};
}

Result<void> CheckReserved(const RecordErrors& errors, uint32_t reserved) {
  if (reserved != 0) {
    return errors.Invalid("reserved", std::to_string(reserved) + " is not 0");
  }
  return {};
}

Result<void> CheckCoordinate(const RecordErrors& errors, const std::string& field, double value,
                             const RingLimits& limits) {
  if (!std::isfinite(value)) {
    return errors.Invalid(field, FormatDouble(value) + " is not finite");
  }
  if (std::abs(value) > limits.max_abs_coordinate) {
    return errors.Invalid(
        field, FormatDouble(value) + " is beyond +-" + FormatDouble(limits.max_abs_coordinate));
  }
  return {};
}

// Reads and checks a pose of 7 doubles at `offset`.
Result<Pose> LoadPose(const RecordErrors& errors, std::span<const uint8_t> bytes, size_t offset,
                      const RingLimits& limits) {
  double v[kPoseDoubles];
  std::memcpy(v, bytes.data() + offset, sizeof(v));
  static const char* const kNames[kPoseDoubles] = {"X_WO.t.x", "X_WO.t.y", "X_WO.t.z", "X_WO.q.w",
                                                   "X_WO.q.x", "X_WO.q.y", "X_WO.q.z"};
  for (int i = 0; i < 3; ++i) {
    if (auto ok = CheckCoordinate(errors, kNames[i], v[i], limits); !ok) return ok.error();
  }
  for (int i = 3; i < kPoseDoubles; ++i) {
    if (!std::isfinite(v[i])) {
      return errors.Invalid(kNames[i], FormatDouble(v[i]) + " is not finite");
    }
  }
  const Pose pose = internal::DecodePose(v);
  // The unit-quaternion rule is the model's (far::CheckPose), as for every other pose. The pose
  // is passed on bit for bit; the pipeline normalizes it where it places the object
  // (scene_cache.cc), as it does for in-process callers, so normalizing happens once.
  if (auto ok = CheckPose(pose); !ok) return errors.Invalid("X_WO", ok.error().message);
  return pose;
}

// Reads and checks `count` positions at `offset` (the caller proved they are in `bytes`).
Result<std::vector<Eigen::Vector3d>> LoadPositions(const RecordErrors& errors,
                                                   std::span<const uint8_t> bytes, size_t offset,
                                                   uint32_t count, const RingLimits& limits) {
  std::vector<Eigen::Vector3d> positions(count);
  std::memcpy(static_cast<void*>(positions.data()), bytes.data() + offset,
              size_t{count} * sizeof(Eigen::Vector3d));
  // Fast path, branch-free so that it vectorizes: |v| <= max is false for NaN and infinities
  // too. Only when some value fails, find it and name it.
  const double* values = positions.empty() ? nullptr : positions.data()->data();
  const size_t num_values = size_t{count} * 3;
  bool all_fine = true;
  for (size_t i = 0; i < num_values; ++i)
    all_fine &= std::abs(values[i]) <= limits.max_abs_coordinate;
  if (all_fine) return positions;
  static const char* const kAxis[3] = {"x", "y", "z"};
  for (uint32_t i = 0; i < count; ++i) {
    for (int k = 0; k < 3; ++k) {
      const double value = positions[i][k];
      if (std::isfinite(value) && std::abs(value) <= limits.max_abs_coordinate) continue;
      const std::string field = "p_MV[" + std::to_string(i) + "]." + kAxis[k];
      if (auto ok = CheckCoordinate(errors, field, value, limits); !ok) return ok.error();
    }
  }
  return positions;
}

template <typename T>
std::span<const uint8_t> BodyOf(const T& record) {
  // Everything after the RecordHeader the ring writes itself.
  return {reinterpret_cast<const uint8_t*>(&record) + sizeof(RecordHeader),
          sizeof(T) - sizeof(RecordHeader)};
}

template <typename T>
std::span<const uint8_t> BytesOf(std::span<const T> values) {
  return {reinterpret_cast<const uint8_t*>(values.data()), values.size_bytes()};
}

// One parser per record type; the header (size, type) is checked by ParseUpdateRecord.
Result<RingUpdate> ParseAddObject(const RecordErrors& errors, std::span<const uint8_t> record,
                                  const RingLimits& limits) {
  if (record.size() < sizeof(AddObjectRecord)) {
    return errors.Invalid(
        "size", std::to_string(record.size()) + " is smaller than an add_object record (88 bytes)");
  }
  const auto fixed = Load<AddObjectRecord>(record, 0);
  if (fixed.motion > static_cast<uint32_t>(WireMotion::kDeformable)) {
    return errors.Invalid(
        "motion", std::to_string(fixed.motion) + " is not 0 (static), 1 (rigid) or 2 (deformable)");
  }
  if (auto ok = CheckCount(errors, "vertex_count", fixed.vertex_count, limits.max_vertices); !ok)
    return ok.error();
  if (auto ok = CheckCount(errors, "triangle_count", fixed.triangle_count, limits.max_triangles);
      !ok) {
    return ok.error();
  }
  // 64-bit: 24 * 2^32 + 12 * 2^32 cannot overflow.
  const uint64_t expected = AddObjectRecordSize(fixed.vertex_count, fixed.triangle_count);
  if (auto ok = CheckSize(errors, static_cast<uint32_t>(record.size()), expected,
                          "vertex_count " + std::to_string(fixed.vertex_count) +
                              " and triangle_count " + std::to_string(fixed.triangle_count));
      !ok) {
    return ok.error();
  }
  auto pose = LoadPose(errors, record, offsetof(AddObjectRecord, X_WO), limits);
  if (!pose) return pose.error();
  auto positions =
      LoadPositions(errors, record, sizeof(AddObjectRecord), fixed.vertex_count, limits);
  if (!positions) return positions.error();
  far::AddObject add{fixed.object_id, {}, static_cast<Motion>(fixed.motion), *pose};
  add.mesh.p_MV = std::move(*positions);
  add.mesh.triangles.resize(fixed.triangle_count);
  const size_t triangles_offset =
      sizeof(AddObjectRecord) + size_t{fixed.vertex_count} * sizeof(Eigen::Vector3d);
  std::memcpy(add.mesh.triangles.data(), record.data() + triangles_offset,
              size_t{fixed.triangle_count} * sizeof(TriangleIndices));
  for (uint32_t t = 0; t < fixed.triangle_count; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = add.mesh.triangles[t][k];
      if (v >= fixed.vertex_count) {
        return errors.Invalid(
            "triangles[" + std::to_string(t) + "][" + std::to_string(k) + "]",
            std::to_string(v) + " is not < vertex_count " + std::to_string(fixed.vertex_count));
      }
    }
  }
  return RingUpdate(std::move(add));
}

Result<RingUpdate> ParseSetPose(const RecordErrors& errors, std::span<const uint8_t> record,
                                const RingLimits& limits) {
  if (auto ok = CheckSize(errors, static_cast<uint32_t>(record.size()), sizeof(SetPoseRecord),
                          "set_pose");
      !ok) {
    return ok.error();
  }
  const auto fixed = Load<SetPoseRecord>(record, 0);
  if (auto ok = CheckReserved(errors, fixed.reserved); !ok) return ok.error();
  auto pose = LoadPose(errors, record, offsetof(SetPoseRecord, X_WO), limits);
  if (!pose) return pose.error();
  return RingUpdate(far::SetPose{fixed.object_id, *pose});
}

Result<RingUpdate> ParseSetVertices(const RecordErrors& errors, std::span<const uint8_t> record,
                                    const RingLimits& limits) {
  if (record.size() < sizeof(SetVerticesRecord)) {
    return errors.Invalid("size", std::to_string(record.size()) +
                                      " is smaller than a set_vertices record (24 bytes)");
  }
  const auto fixed = Load<SetVerticesRecord>(record, 0);
  if (auto ok = CheckCount(errors, "vertex_count", fixed.vertex_count, limits.max_vertices); !ok)
    return ok.error();
  if (auto ok = CheckSize(errors, static_cast<uint32_t>(record.size()),
                          SetVerticesRecordSize(fixed.vertex_count),
                          "vertex_count " + std::to_string(fixed.vertex_count));
      !ok) {
    return ok.error();
  }
  auto positions =
      LoadPositions(errors, record, sizeof(SetVerticesRecord), fixed.vertex_count, limits);
  if (!positions) return positions.error();
  return RingUpdate(far::SetVertices{fixed.object_id, std::move(*positions)});
}

}  // namespace

Result<RingUpdate> ParseUpdateRecord(std::span<const uint8_t> record, const RingLimits& limits) {
  if (record.size() < sizeof(RecordHeader)) {
    return MakeError(ErrorCode::kInvalidArgument, "update ring: a record of " +
                                                      std::to_string(record.size()) +
                                                      " bytes is shorter than its header");
  }
  const auto header = Load<RecordHeader>(record, 0);
  const RecordErrors errors(header);
  if (header.size != record.size()) {
    return errors.Invalid("size", std::to_string(header.size) + " differs from the " +
                                      std::to_string(record.size()) + " bytes copied");
  }
  switch (static_cast<RecordType>(header.type)) {
    case RecordType::kAddObject:
      return ParseAddObject(errors, record, limits);
    case RecordType::kRemoveObject: {
      if (auto ok = CheckSize(errors, header.size, sizeof(RemoveObjectRecord), "remove_object");
          !ok) {
        return ok.error();
      }
      const auto fixed = Load<RemoveObjectRecord>(record, 0);
      if (auto ok = CheckReserved(errors, fixed.reserved); !ok) return ok.error();
      return RingUpdate(far::RemoveObject{fixed.object_id});
    }
    case RecordType::kSetPose:
      return ParseSetPose(errors, record, limits);
    case RecordType::kSetVertices:
      return ParseSetVertices(errors, record, limits);
    case RecordType::kStepReply:
      break;
  }
  return errors.Invalid("type", std::to_string(header.type) +
                                    " is not an update record type (1 add_object, 2 "
                                    "remove_object, 3 set_pose, 4 set_vertices)");
}

// ---- UpdateWriter ----------------------------------------------------------------------------

namespace {

Result<RecordPosition> WriteRecord(RingWriter& ring, RecordType type,
                                   std::initializer_list<std::span<const uint8_t>> body,
                                   std::chrono::milliseconds timeout) {
  if (timeout.count() > 0) return ring.WriteWait(type, body, timeout);
  return ring.Write(type, body);
}

}  // namespace

Result<RecordPosition> UpdateWriter::AddObject(uint32_t id, const Mesh& mesh, Motion motion,
                                               const Pose& X_WO,
                                               std::chrono::milliseconds timeout) {
  if (mesh.p_MV.size() > UINT32_MAX || mesh.triangles.size() > UINT32_MAX) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "add_object: more than 2^32 - 1 vertices or triangles");
  }
  AddObjectRecord fixed{};
  fixed.object_id = id;
  fixed.motion = static_cast<uint32_t>(motion);
  fixed.vertex_count = static_cast<uint32_t>(mesh.p_MV.size());
  fixed.triangle_count = static_cast<uint32_t>(mesh.triangles.size());
  internal::EncodePose(X_WO, fixed.X_WO);
  return WriteRecord(ring_, RecordType::kAddObject,
                     {BodyOf(fixed), BytesOf(std::span<const Eigen::Vector3d>(mesh.p_MV)),
                      BytesOf(std::span<const TriangleIndices>(mesh.triangles))},
                     timeout);
}

Result<RecordPosition> UpdateWriter::RemoveObject(uint32_t id, std::chrono::milliseconds timeout) {
  RemoveObjectRecord fixed{};
  fixed.object_id = id;
  return WriteRecord(ring_, RecordType::kRemoveObject, {BodyOf(fixed)}, timeout);
}

Result<RecordPosition> UpdateWriter::SetPose(uint32_t id, const Pose& X_WO,
                                             std::chrono::milliseconds timeout) {
  SetPoseRecord fixed{};
  fixed.object_id = id;
  internal::EncodePose(X_WO, fixed.X_WO);
  return WriteRecord(ring_, RecordType::kSetPose, {BodyOf(fixed)}, timeout);
}

Result<RecordPosition> UpdateWriter::SetVertices(uint32_t id, std::span<const Eigen::Vector3d> p_MV,
                                                 std::chrono::milliseconds timeout) {
  if (p_MV.size() > UINT32_MAX) {
    return MakeError(ErrorCode::kInvalidArgument, "set_vertices: more than 2^32 - 1 vertices");
  }
  SetVerticesRecord fixed{};
  fixed.object_id = id;
  fixed.vertex_count = static_cast<uint32_t>(p_MV.size());
  return WriteRecord(ring_, RecordType::kSetVertices, {BodyOf(fixed), BytesOf(p_MV)}, timeout);
}

// ---- UpdateReader ----------------------------------------------------------------------------

UpdateReader::UpdateReader(RingRegion region, RingLimits limits)
    // A record is never larger than the ring; counts over the limits get a content error
    // from ParseUpdateRecord (framing stays intact), not a framing error.
    : ring_(std::move(region), UINT64_MAX), limits_(limits) {}

Result<std::vector<SequencedUpdate>> UpdateReader::Drain(uint64_t up_to_sequence) {
  const uint64_t first = ring_.last_sequence() + 1;
  auto records = ring_.ReadUpTo(up_to_sequence);
  if (!records) return records.error();
  std::vector<SequencedUpdate> updates;
  updates.reserve(records->size());
  for (const RawRecord& record : *records) {
    auto update = ParseUpdateRecord(record.bytes, limits_);
    if (!update) {
      // All-or-nothing: the step's records are consumed and none is applied.
      Error error = update.error();
      error.message += "; records " + std::to_string(first) + ".." +
                       std::to_string(up_to_sequence) + " of this step were discarded";
      return error;
    }
    updates.push_back({record.header.sequence, std::move(*update)});
  }
  return updates;
}

}  // namespace far::protocol
