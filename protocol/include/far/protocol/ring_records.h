#pragma once

// The update ring's records as far's types: the client writes them with UpdateWriter, the
// daemon drains and validates them with UpdateReader.
//
// What "nothing is lost" means when a record is bad (docs/protocol.md):
//   - A record whose content is bad (NaN, index out of range, count over a limit, unknown
//     type, sizes that do not match the counts) has intact framing. Drain is all-or-nothing
//     per step: it returns the error naming the record and consumes the step's records
//     (last_sequence()+1 .. ring_commit_sequence); none of them is returned, so the scene
//     stays as it was after the previous step and the client knows exactly which records to
//     write again (the error names the range). The session goes on.
//   - A framing error (indices, sizes, sequences) loses the record boundaries: the ring is
//     corrupt and every later Drain returns the same error; updates applied by earlier steps
//     stay. The client must open a new session.
//   - A commit sequence beyond what was written consumes nothing (kInvalidArgument).
// Checks that need the scene (object alive, motion kind, vertex count of an existing object)
// are far::SceneModel's, when the daemon applies the updates in order (far::Pipeline::Apply).

#include <chrono>
#include <cstdint>
#include <span>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "far/base/limits.h"
#include "far/base/result.h"
#include "far/model/mesh.h"
#include "far/model/scene_update.h"
#include "far/protocol/ring.h"
#include "far/protocol/ring_layout.h"

namespace far::protocol {

/// What the daemon accepts from a client's update ring.
struct RingLimits {
  uint32_t max_vertices = 1u << 22;            ///< per add_object / set_vertices record
  uint32_t max_triangles = 1u << 22;           ///< per add_object record
  double max_abs_coordinate = kMaxCoordinate;  ///< |x|, |y|, |z| of positions and translations
};

/// A record's update: far's own update types (far/model/scene_update.h).
using RingUpdate = SceneUpdate;

/// A validated update and the record it came from.
struct SequencedUpdate {
  uint64_t sequence = 0;
  RingUpdate update;
};

/// Parses and validates one record (a private copy: RawRecord::bytes; its header already
/// framing-checked by RingReader). Checks: known update type, size equal to the size its
/// counts imply (64-bit arithmetic), counts in [1, limit], reserved fields zero, every double
/// finite and within max_abs_coordinate, poses by far::CheckPose (quaternion norm within
/// kQuaternionTolerance of 1; passed on as sent, far::Pipeline normalizes), motion known, every
/// triangle index < vertex_count. Every uint32 is a valid object id. Errors (message names the
/// record sequence, the field and the value): kInvalidArgument, kLimitExceeded for counts over
/// limits.
Result<RingUpdate> ParseUpdateRecord(std::span<const uint8_t> record, const RingLimits& limits);

/// The client side of the update ring. Each call writes one record and publishes it; put
/// last_sequence() into step_request_t.ring_commit_sequence. With timeout 0 a full ring is
/// kBusy; otherwise it waits up to `timeout` (kTimeout). Errors also: kLimitExceeded (record
/// larger than the ring), kInvalidArgument (more than 2^32-1 vertices or triangles).
/// Thread safety: one thread at a time.
class UpdateWriter {
 public:
  explicit UpdateWriter(RingRegion region) : ring_(std::move(region)) {}

  Result<RecordPosition> AddObject(uint32_t id, const Mesh& mesh, Motion motion, const Pose& X_WO,
                                   std::chrono::milliseconds timeout = {});
  Result<RecordPosition> RemoveObject(uint32_t id, std::chrono::milliseconds timeout = {});
  Result<RecordPosition> SetPose(uint32_t id, const Pose& X_WO,
                                 std::chrono::milliseconds timeout = {});
  Result<RecordPosition> SetVertices(uint32_t id, std::span<const Eigen::Vector3d> p_MV,
                                     std::chrono::milliseconds timeout = {});

  uint64_t last_sequence() const { return ring_.last_sequence(); }
  RingWriter& ring() { return ring_; }

 private:
  RingWriter ring_;
};

/// The daemon side of the update ring. Thread safety: one thread at a time.
class UpdateReader {
 public:
  UpdateReader(RingRegion region, RingLimits limits);

  /// Copies the records last_sequence()+1 .. up_to_sequence out of the ring and validates
  /// them (all-or-nothing, see the top of this file). Returns them in ring order.
  /// Errors: those of RingReader::ReadUpTo and ParseUpdateRecord; a content error says which
  /// records were discarded.
  Result<std::vector<SequencedUpdate>> Drain(uint64_t up_to_sequence);

  uint64_t last_sequence() const { return ring_.last_sequence(); }
  bool corrupt() const { return ring_.corrupt(); }
  RingReader& ring() { return ring_; }

 private:
  RingReader ring_;
  RingLimits limits_;
};

}  // namespace far::protocol
