// Fuzz target ring_record: one update-ring record as the daemon parses it (ParseUpdateRecord
// with the daemon's default RingLimits), then applied to a session's scene (SceneModel::Apply
// within the daemon's default session limits) that already holds a static, a rigid and a
// deformable object, so that every record type meets live objects. ring_reader fuzzes the
// framing around records; this target reaches the record contents without it.
//
// Input: uint8 flags, then the record bytes (header included). flags bit 0: the harness writes
// the record's true size into its header (framing guarantees that much; clear, the header's
// size is the input's and usually wrong).
//
// Oracle besides the sanitizers: a record that parses is written back by the client's writer
// (UpdateWriter) as a record of the same size that parses again to a record written the same.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <variant>
#include <vector>

#include "daemon_config.h"
#include "fuzz_input.h"
#include "protocol/test_ring.h"

#include "far/model/scene_model.h"
#include "far/protocol/ring_records.h"

namespace far::fuzz {
namespace {

using protocol::testing::TestRing;

Mesh Tetrahedron() {
  Mesh mesh;
  mesh.p_MV = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return mesh;
}

// The record the client's writer makes of `update`, copied out of a private ring.
std::vector<uint8_t> Written(const SceneUpdate& update) {
  TestRing ring(protocol::kMinRingCapacity);
  protocol::UpdateWriter writer(ring.region());
  auto at = std::visit(
      [&](const auto& u) -> Result<protocol::RecordPosition> {
        using T = std::decay_t<decltype(u)>;
        if constexpr (std::is_same_v<T, AddObject>) {
          return writer.AddObject(u.id, u.mesh, u.motion, u.X_WO);
        } else if constexpr (std::is_same_v<T, RemoveObject>) {
          return writer.RemoveObject(u.id);
        } else if constexpr (std::is_same_v<T, SetPose>) {
          return writer.SetPose(u.id, u.X_WO);
        } else {
          return writer.SetVertices(u.id, u.p_MV);
        }
      },
      update);
  if (!at) return {};  // larger than the ring: nothing to compare
  std::vector<uint8_t> bytes(at->size);
  for (uint64_t i = 0; i < at->size; ++i)
    bytes[i] = ring.data[(at->index + i) & (ring.data.size() - 1)];
  return bytes;
}

void CheckRewrite(const SceneUpdate& update, size_t size, const protocol::RingLimits& limits) {
  const std::vector<uint8_t> once = Written(update);
  if (once.empty()) return;
  FAR_FUZZ_CHECK(once.size() == size);
  auto again = protocol::ParseUpdateRecord(once, limits);
  FAR_FUZZ_CHECK(again);
  FAR_FUZZ_CHECK(Written(*again) == once);
}

}  // namespace
}  // namespace far::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace far;
  using namespace far::fuzz;
  if (size == 0) return 0;
  std::vector<uint8_t> record(data + 1, data + size);
  if ((data[0] & 1) != 0 && record.size() >= sizeof(protocol::RecordHeader)) {
    const auto bytes = static_cast<uint32_t>(record.size());
    std::memcpy(record.data() + offsetof(protocol::RecordHeader, size), &bytes, sizeof(bytes));
  }
  static const server::DaemonConfig config;
  static const protocol::RingLimits limits = server::RingLimitsOf(config);
  auto update = protocol::ParseUpdateRecord(record, limits);
  if (!update) return 0;
  CheckRewrite(*update, record.size(), limits);
  SharedSceneBudget budget(config.max_vertices_total, config.max_triangles_total);
  FAR_FUZZ_CHECK(budget.Admit(1, 0, {}));  // the session's holder
  SceneModel scene(server::SceneLimitsOf(config), &budget, 1);
  const Mesh mesh = Tetrahedron();
  const SceneUpdate setup[] = {AddObject{1, mesh, Motion::kStatic, Pose{}},
                               AddObject{2, mesh, Motion::kRigid, Pose{}},
                               AddObject{3, mesh, Motion::kDeformable, Pose{}}};
  FAR_FUZZ_CHECK(scene.Apply(setup));
  (void)scene.Apply(std::span<const SceneUpdate>(&*update, 1));
  return 0;
}
