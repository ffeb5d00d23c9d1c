// Fuzz target bvh_reference: the bvh method's hierarchy stage (TriangleBvh, then RunBvhTests)
// against the brute-force reference (BruteForceReference), the oracle every culling path answers
// to, on small scenes the bytes describe. The bytes reach the hard cases directly: corners on a
// grid, so that corners, edges and planes of different objects coincide exactly (touching and
// coplanar pairs, degenerate triangles); corners of an earlier object carried into this
// object's frame through its rounded inverse pose (contact through rounded poses); rotated and
// unrotated poses (the stage's two descents); scales from 2^-20 to 2^10, shifted up to 1e7 from
// the origin, and tiny scales whose world corners lie around and below kTinyWorldCoordinate (the
// pipeline takes those as 0, and the descent's margin must cover it); distance queries; trees
// without slabs (refit); one thread or two.
//
// Input, front to back (past the end every byte reads as 0):
//   uint8 flags: bit 0 a distance query, bit 1 refit the trees (no slabs), bit 2 one thread
//         (else two), bits 3-5 the shift s (kShifts) along (1, -0.5, 0.25)
//   int8  scale exponent: scale = 2^clamp(e, -20, 10), or 2^(e - 188) for e < -64 (2^-316 to
//         2^-253: corners from 2^-320 to 2^-250, the largest around kTinyWorldCoordinate =
//         2^-256, the rest below); the grid step is scale / 16
//   uint8 distance: D = scale * d / 64 (with flag bit 0)
//   uint8 objects: 2 + n % 3, then per object:
//     uint8 vertices: 3 + n % 14;  uint8 triangles: 1 + n % 12
//     uint8 pose flags: bit 0 the identity rotation
//     int8 x 4 quaternion w, x, y, z (normalized; all zero: the identity)
//     int8 x 3 translation, in grid steps (plus the shift)
//     per vertex: uint8 kind. Bit 7 set (and an earlier object): the earlier object's world
//       corner (kind & 0x7f) mod its count, carried into this object's frame; else int8 x 3,
//       the corner in grid steps
//     per triangle: uint8 x 3 corner indices (mod vertices)
//
// Oracles besides the sanitizers: bvh's contacts are the reference's, pair for pair; with a
// distance, so are its distance pairs' triangle pairs; every contact's two triangles are among
// bvh's candidates; nothing stops early.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz_grid.h"
#include "fuzz_input.h"
#include <Eigen/Geometry>

#include "far/base/thread_pool.h"
#include "far/pairs/bvh_stage.h"
#include "far/pairs/exact_stage.h"
#include "far/pairs/triangle_bvh.h"

namespace far::fuzz {
namespace {

struct Object {
  std::vector<Eigen::Vector3d> p_MV, p_WV;
  std::vector<TriangleIndices> triangles;
  Eigen::Isometry3d X_WM = Eigen::Isometry3d::Identity();
  TriangleBvh bvh;
};

Object ReadObject(FuzzInput& in, double step, const Eigen::Vector3d& shift,
                  const std::vector<Object>& earlier) {
  Object object;
  const int vertices = 3 + in.Take<uint8_t>() % 14;
  const int triangles = 1 + in.Take<uint8_t>() % 12;
  const bool unrotated = in.Take<uint8_t>() & 1;
  // One read per statement: the order of a call's arguments is unspecified.
  const double w = in.Take<int8_t>(), x = in.Take<int8_t>(), y = in.Take<int8_t>(),
               z = in.Take<int8_t>();
  Eigen::Quaterniond q(w, x, y, z);
  if (unrotated || q.squaredNorm() == 0) q = Eigen::Quaterniond::Identity();
  object.X_WM.linear() = q.normalized().toRotationMatrix();
  object.X_WM.translation() = GridPoint(in, step) + shift;
  const Eigen::Isometry3d X_MW = object.X_WM.inverse();
  for (int v = 0; v < vertices; ++v) {
    const uint8_t kind = in.Take<uint8_t>();
    if ((kind & 0x80) != 0 && !earlier.empty()) {
      const Object& other = earlier.back();
      object.p_MV.push_back(X_MW * other.p_WV[(kind & 0x7f) % other.p_WV.size()]);
    } else {
      object.p_MV.push_back(GridPoint(in, step));
    }
  }
  for (int t = 0; t < triangles; ++t) {
    const auto corner = [&] { return static_cast<uint32_t>(in.Take<uint8_t>() % vertices); };
    const uint32_t a = corner(), b = corner(), c = corner();
    object.triangles.push_back({a, b, c});
  }
  // As the pipeline places an object: the world corners are X_WM applied to the mesh's, with
  // tiny coordinates taken as 0.
  for (const Eigen::Vector3d& p : object.p_MV) object.p_WV.push_back(WorldVertex(object.X_WM, p));
  return object;
}

}  // namespace
}  // namespace far::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace far;
  using namespace far::fuzz;
  static ThreadPool one(1), two(2);
  FuzzInput in(data, size);
  const uint8_t flags = in.Take<uint8_t>();
  const int exponent = in.Take<int8_t>();
  const double scale = GridScale(exponent);
  const double distance = scale * in.Take<uint8_t>() / 64;
  const std::optional<double> max_distance =
      flags & 1 ? std::optional<double>(distance) : std::nullopt;
  const bool refit = flags & 2;
  ThreadPool& pool = flags & 4 ? one : two;
  const Eigen::Vector3d shift = GridShift((flags >> 3) & 7);
  const int count = 2 + in.Take<uint8_t>() % 3;

  std::vector<Object> objects;
  for (int o = 0; o < count; ++o) {
    objects.push_back(ReadObject(in, scale / 16, shift, objects));
    Object& object = objects.back();
    object.bvh.Build(object.p_MV, object.triangles);
    if (refit) FAR_FUZZ_CHECK(!object.bvh.Refit(object.p_MV, object.triangles));
  }

  std::vector<WorldObjectView> views;
  std::vector<ObjectHierarchy> hierarchies;
  std::vector<SlotPair> pairs;
  for (size_t o = 0; o < objects.size(); ++o) {
    views.push_back({objects[o].p_WV, objects[o].triangles});
    hierarchies.push_back({&objects[o].bvh, objects[o].X_WM});
    for (size_t later = o + 1; later < objects.size(); ++later)
      pairs.push_back({SlotAt(o), SlotAt(later)});
  }
  BvhQuery query;
  query.objects = views;
  query.hierarchies = hierarchies;
  query.object_pairs = pairs;
  query.max_distance = max_distance;
  const BvhResult found = RunBvhTests(query, pool);
  const ExactResult expected = BruteForceReference(views, max_distance, pool);

  FAR_FUZZ_CHECK(found.exact.stopped == StopReason::kNone);
  FAR_FUZZ_CHECK(found.exact.contacts == expected.contacts);
  FAR_FUZZ_CHECK(PairsOf(found.exact.distance_pairs) == PairsOf(expected.distance_pairs));
  for (const SlotContact& c : expected.contacts) {
    const auto candidate = [&](ObjectSlot slot, uint32_t triangle) {
      const size_t o = Index(slot);
      return std::binary_search(found.candidates[o].begin(), found.candidates[o].end(), triangle);
    };
    FAR_FUZZ_CHECK(candidate(c.object_a, c.triangle_a) && candidate(c.object_b, c.triangle_b));
  }
  return 0;
}
