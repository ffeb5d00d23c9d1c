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
// auto answer what exact answers, pair for pair.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include "fuzz_input.h"
#include <Eigen/Geometry>

#include "far/pipeline/pipeline.h"

namespace far::fuzz {
namespace {

Eigen::Vector3d GridPoint(FuzzInput& in, double step) {
  const double x = in.Take<int8_t>(), y = in.Take<int8_t>(), z = in.Take<int8_t>();
  return Eigen::Vector3d(x, y, z) * step;
}

Pose ReadPose(FuzzInput& in, double step) {
  // One read per statement: the order of a call's arguments is unspecified.
  const double w = in.Take<int8_t>(), x = in.Take<int8_t>(), y = in.Take<int8_t>(),
               z = in.Take<int8_t>();
  Pose pose;
  Eigen::Quaterniond q(w, x, y, z);
  pose.rotation = q.squaredNorm() == 0 ? Eigen::Quaterniond::Identity() : q.normalized();
  pose.translation = GridPoint(in, step);
  return pose;
}

std::vector<Eigen::Vector3d> ReadVertices(FuzzInput& in, size_t count, double step) {
  std::vector<Eigen::Vector3d> p_MV;
  for (size_t v = 0; v < count; ++v) p_MV.push_back(GridPoint(in, step));
  return p_MV;
}

struct Object {
  uint32_t id = 0;
  Motion motion = Motion::kStatic;
  Mesh mesh;
  Pose pose;
};

Object ReadObject(FuzzInput& in, uint32_t id, double step) {
  Object object;
  object.id = id;
  constexpr Motion kMotions[] = {Motion::kStatic, Motion::kRigid, Motion::kDeformable};
  object.motion = kMotions[in.Take<uint8_t>() % 3];
  const size_t vertices = 3 + in.Take<uint8_t>() % 10;
  const int triangles = 1 + in.Take<uint8_t>() % 8;
  object.pose = ReadPose(in, step);
  object.mesh.p_MV = ReadVertices(in, vertices, step);
  for (int t = 0; t < triangles; ++t) {
    const auto corner = [&] { return static_cast<uint32_t>(in.Take<uint8_t>() % vertices); };
    const uint32_t a = corner(), b = corner(), c = corner();
    object.mesh.triangles.push_back({a, b, c});
  }
  return object;
}

// One later step's change to `object` (see the layout above).
void Change(FuzzInput& in, double step, Object& object, Pipeline& pipeline) {
  const uint8_t change = in.Take<uint8_t>() % 4;
  if (change == 1 && object.motion != Motion::kStatic) {
    object.pose = ReadPose(in, step);
    FAR_FUZZ_CHECK(pipeline.SetPose(object.id, object.pose).ok());
  } else if (change == 2 && object.motion == Motion::kDeformable) {
    object.mesh.p_MV = ReadVertices(in, object.mesh.p_MV.size(), step);
    FAR_FUZZ_CHECK(pipeline.SetVertices(object.id, object.mesh.p_MV).ok());
  } else if (change == 3) {
    FAR_FUZZ_CHECK(pipeline.RemoveObject(object.id).ok());
    FAR_FUZZ_CHECK(pipeline.AddObject(object.id, object.mesh, object.motion, object.pose).ok());
  }
}

std::vector<ContactPair> PairsOf(const std::vector<DistancePair>& list) {
  std::vector<ContactPair> pairs;
  for (const DistancePair& d : list) pairs.push_back(d.pair);
  return pairs;
}

// Every reliable CPU method against exact, on the scene as it stands.
void CheckStep(Pipeline& pipeline, const std::optional<double>& distance) {
  StepRequest request;
  request.distance = distance;
  request.output = distance ? Output::kDistancePairs : Output::kContacts;
  request.method = Method::kExact;
  const Result<StepResult> expected = pipeline.Step(request);
  FAR_FUZZ_CHECK(expected.ok());
  for (const Method method : {Method::kBvh, Method::kAabb, Method::kAuto}) {
    request.method = method;
    const Result<StepResult> found = pipeline.Step(request);
    FAR_FUZZ_CHECK(found.ok());
    FAR_FUZZ_CHECK(found->contacts == expected->contacts);
    FAR_FUZZ_CHECK(PairsOf(found->distance_pairs) == PairsOf(expected->distance_pairs));
  }
}

}  // namespace
}  // namespace far::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace far;
  using namespace far::fuzz;
  FuzzInput in(data, size);
  const uint8_t flags = in.Take<uint8_t>();
  const int exponent = in.Take<int8_t>();
  const double scale =
      std::ldexp(1.0, exponent < -64 ? exponent - 188 : std::clamp(exponent, -20, 10));
  const double step = scale / 16;
  const double d = scale * in.Take<uint8_t>() / 64;
  const std::optional<double> distance = flags & 1 ? std::optional<double>(d) : std::nullopt;
  const int later_steps = (flags >> 1) & 3;

  PipelineOptions options;
  options.use_gl = false;
  options.num_threads = 2;
  auto pipeline = Pipeline::Create(options);
  FAR_FUZZ_CHECK(pipeline.ok());
  std::vector<Object> objects;
  const int count = 2 + in.Take<uint8_t>() % 3;
  for (int o = 0; o < count; ++o) {
    objects.push_back(ReadObject(in, static_cast<uint32_t>(1 + 2 * o), step));
    const Object& object = objects.back();
    FAR_FUZZ_CHECK((*pipeline)->AddObject(object.id, object.mesh, object.motion, object.pose).ok());
  }
  CheckStep(**pipeline, distance);
  for (int s = 0; s < later_steps; ++s) {
    for (Object& object : objects) Change(in, step, object, **pipeline);
    CheckStep(**pipeline, distance);
  }
  return 0;
}
