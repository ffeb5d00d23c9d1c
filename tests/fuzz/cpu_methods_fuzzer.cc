// Fuzz target cpu_methods: a far::Pipeline without GL, as the daemon runs one for a session on a
// host without a GPU, stepped through a few frames of a small scene the bytes describe. At every
// step each reliable CPU method (bvh, aabb, and auto, which runs one of them) must give exactly
// the contacts (and, with a distance, the distance pairs) of the brute-force reference `exact`,
// on the same pipeline, so that everything between an update and an answer is held to the
// oracle: the scene model's checks, pose normalization, the world vertices (and their flush of
// tiny coordinates), the sweep-and-prune kept across steps, hierarchies built once for static
// and rigid objects and refit for deformable ones, and the exact stage.
//
// Input, front to back (past the end every byte reads as 0):
//   uint8 flags: bit 0 a distance query, bits 1-2 the steps after the first (0-3)
//   int8  scale exponent, as bvh_reference: 2^clamp(e, -20, 10), or 2^(e - 188) for e < -64;
//         the grid step is scale / 16
//   uint8 distance: D = scale * d / 64 (with flag bit 0)
//   uint8 objects: 2 + n % 3, then per object:
//     uint8 motion (n % 3: static, rigid, deformable); uint8 vertices: 3 + n % 10;
//     uint8 triangles: 1 + n % 8; a pose (int8 x 4 quaternion w, x, y, z, all zero: the
//     identity; int8 x 3 translation in grid steps); per vertex int8 x 3 in grid steps; per
//     triangle uint8 x 3 corner indices (mod vertices)
//   per later step, per object: uint8 change (n % 4: none, a new pose, new vertices, removed
//     and added again with the same mesh), then what the change needs (a pose as above; the
//     vertices as above). A static object takes no pose and no vertices, a rigid one no
//     vertices: those changes are skipped.
//
// Oracles besides the sanitizers: every update is accepted; every step succeeds; bvh, aabb and
// auto answer what exact answers, pair for pair; the geometry of bvh's answer is well formed
// (CheckGeometry). The reading of the bytes and the oracle are in
// fuzz_scene.h, shared with gl_methods.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>

#include "fuzz_input.h"
#include "fuzz_scene.h"

#include "far/pipeline/pipeline.h"

namespace far::fuzz {
namespace {

// The geometry stage on the same step: arrays parallel to the pairs, counts in range, normals
// unit or zero, every number finite, closest points as far apart as the reported distance,
// depths >= 0 with unit directions. (Points against the exact intersection are checked by
// far_geometry_test's rational reference; here the sanitizers watch the stage on hostile
// scenes: tiny scales, degenerate and coincident triangles, objects removed and added again.)
void CheckGeometry(Pipeline& pipeline, StepRequest request) {
  request.method = Method::kBvh;
  request.geometry = true;
  const Result<StepResult> found = pipeline.Step(request);
  FAR_FUZZ_CHECK(found.ok());
  const StepResult& r = *found;
  FAR_FUZZ_CHECK(r.contact_geometry.size() == r.contacts.size());
  FAR_FUZZ_CHECK(r.closest_points.size() == r.distance_pairs.size());
  const auto finite = [](const Eigen::Vector3d& p) { return p.allFinite(); };
  const auto unit_or_zero = [](const Eigen::Vector3d& n) {
    return n == Eigen::Vector3d::Zero() || std::abs(n.norm() - 1.0) < 1e-12;
  };
  for (const ContactGeometry& g : r.contact_geometry) {
    FAR_FUZZ_CHECK(g.num_points >= 1 && g.num_points <= ContactGeometry::kMaxPoints);
    for (int k = 0; k < g.num_points; ++k) FAR_FUZZ_CHECK(finite(g.points[k]));
    FAR_FUZZ_CHECK(unit_or_zero(g.normal_a) && unit_or_zero(g.normal_b));
  }
  for (size_t i = 0; i < r.closest_points.size(); ++i) {
    const ClosestPoints& c = r.closest_points[i];
    FAR_FUZZ_CHECK(finite(c.point_a) && finite(c.point_b));
    const double length = (c.point_b - c.point_a).norm();
    const double d = r.distance_pairs[i].distance;
    const double scale =
        std::max({c.point_a.cwiseAbs().maxCoeff(), c.point_b.cwiseAbs().maxCoeff(), d});
    FAR_FUZZ_CHECK(std::abs(length - d) <= 1e-12 * scale + 1e-300);
  }
  for (const Penetration& p : r.penetrations) {
    FAR_FUZZ_CHECK(std::isfinite(p.depth) && p.depth >= 0);
    FAR_FUZZ_CHECK(p.depth == 0 ? p.direction == Eigen::Vector3d::Zero()
                                : std::abs(p.direction.norm() - 1.0) < 1e-12);
  }
}

// Every reliable CPU method against exact, on the scene as it stands.
void CheckStep(Pipeline& pipeline, const std::optional<double>& distance) {
  StepRequest request;
  request.distance = distance;
  request.output = distance ? Output::kDistancePairs : Output::kContacts;
  const StepResult expected = ExpectedAnswer(pipeline, request);
  for (const Method method : {Method::kBvh, Method::kAabb, Method::kAuto}) {
    request.method = method;
    CheckAnswer(pipeline, request, expected);
  }
  CheckGeometry(pipeline, request);
}

}  // namespace
}  // namespace far::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace far;
  using namespace far::fuzz;
  FuzzInput in(data, size);
  const SceneSpec spec = ReadSceneSpec(in);
  PipelineOptions options;
  options.use_gl = false;
  options.num_threads = 2;
  auto pipeline = Pipeline::Create(options);
  FAR_FUZZ_CHECK(pipeline.ok());
  StepScene(in, spec, **pipeline, [&] { CheckStep(**pipeline, spec.distance); });
  return 0;
}
