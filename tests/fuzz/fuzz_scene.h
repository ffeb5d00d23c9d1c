#pragma once

// Shared by the pipeline fuzz targets (cpu_methods, gl_methods): a small scene the bytes
// describe, stepped through a few frames of updates, and the check that a method answers what
// the brute-force reference answers. The layout is documented once, in cpu_methods_fuzzer.cc;
// gl_methods reads a header of its own, then the same bytes.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <iterator>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fuzz_grid.h"
#include "fuzz_input.h"
#include <Eigen/Geometry>

#include "far/pipeline/pipeline.h"

namespace far::fuzz {

/// Where the scene's grid lies: its step (the scale / 16), and a shift added to every
/// translation (0 for cpu_methods; gl_methods moves whole scenes far from the origin).
struct Grid {
  double step = 1;
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
};

inline Pose ReadPose(FuzzInput& in, const Grid& grid) {
  // One read per statement: the order of a call's arguments is unspecified.
  const double w = in.Take<int8_t>(), x = in.Take<int8_t>(), y = in.Take<int8_t>(),
               z = in.Take<int8_t>();
  Pose pose;
  Eigen::Quaterniond q(w, x, y, z);
  pose.rotation = q.squaredNorm() == 0 ? Eigen::Quaterniond::Identity() : q.normalized();
  pose.translation = GridPoint(in, grid.step) + grid.shift;
  return pose;
}

inline std::vector<Eigen::Vector3d> ReadVertices(FuzzInput& in, size_t count, double step) {
  std::vector<Eigen::Vector3d> p_MV;
  for (size_t v = 0; v < count; ++v) p_MV.push_back(GridPoint(in, step));
  return p_MV;
}

struct SceneObject {
  uint32_t id = 0;
  Motion motion = Motion::kStatic;
  Mesh mesh;
  Pose pose;
};

inline SceneObject ReadObject(FuzzInput& in, uint32_t id, const Grid& grid) {
  SceneObject object;
  object.id = id;
  constexpr Motion kMotions[] = {Motion::kStatic, Motion::kRigid, Motion::kDeformable};
  object.motion = kMotions[in.Take<uint8_t>() % 3];
  const size_t vertices = 3 + in.Take<uint8_t>() % 10;
  const int triangles = 1 + in.Take<uint8_t>() % 8;
  object.pose = ReadPose(in, grid);
  object.mesh.p_MV = ReadVertices(in, vertices, grid.step);
  for (int t = 0; t < triangles; ++t) {
    const auto corner = [&] { return static_cast<uint32_t>(in.Take<uint8_t>() % vertices); };
    const uint32_t a = corner(), b = corner(), c = corner();
    object.mesh.triangles.push_back({a, b, c});
  }
  return object;
}

/// Reads 2 to 4 objects and adds them to `pipeline`; every one must be accepted.
inline std::vector<SceneObject> ReadScene(FuzzInput& in, const Grid& grid, Pipeline& pipeline) {
  std::vector<SceneObject> objects;
  const int count = 2 + in.Take<uint8_t>() % 3;
  for (int o = 0; o < count; ++o) {
    objects.push_back(ReadObject(in, static_cast<uint32_t>(1 + 2 * o), grid));
    const SceneObject& object = objects.back();
    FAR_FUZZ_CHECK(pipeline.AddObject(object.id, object.mesh, object.motion, object.pose).ok());
  }
  return objects;
}

/// One later step's change to `object`: none, a new pose, new vertices, or removed and added
/// again. A static object takes no pose and no vertices, a rigid one no vertices: those changes
/// are skipped. Every update must be accepted.
inline void ReadChange(FuzzInput& in, const Grid& grid, SceneObject& object, Pipeline& pipeline) {
  const uint8_t change = in.Take<uint8_t>() % 4;
  if (change == 1 && object.motion != Motion::kStatic) {
    object.pose = ReadPose(in, grid);
    FAR_FUZZ_CHECK(pipeline.SetPose(object.id, object.pose).ok());
  } else if (change == 2 && object.motion == Motion::kDeformable) {
    object.mesh.p_MV = ReadVertices(in, object.mesh.p_MV.size(), grid.step);
    FAR_FUZZ_CHECK(pipeline.SetVertices(object.id, object.mesh.p_MV).ok());
  } else if (change == 3) {
    FAR_FUZZ_CHECK(pipeline.RemoveObject(object.id).ok());
    FAR_FUZZ_CHECK(pipeline.AddObject(object.id, object.mesh, object.motion, object.pose).ok());
  }
}

/// The scene's first bytes: flags (bit 0 a distance query, bits 1-2 the steps after the first),
/// the scale exponent and the distance (layout in cpu_methods_fuzzer.cc).
struct SceneSpec {
  Grid grid;
  std::optional<double> distance;
  int later_steps = 0;
};

inline SceneSpec ReadSceneSpec(FuzzInput& in) {
  SceneSpec spec;
  const uint8_t flags = in.Take<uint8_t>();
  const int exponent = in.Take<int8_t>();
  const double scale = GridScale(exponent);
  spec.grid.step = scale / 16;
  const double d = scale * in.Take<uint8_t>() / 64;
  if (flags & 1) spec.distance = d;
  spec.later_steps = (flags >> 1) & 3;
  return spec;
}

/// Reads the scene into `pipeline` and calls `check` on it, then after each later step's
/// changes (one per object).
template <typename Check>
void StepScene(FuzzInput& in, const SceneSpec& spec, Pipeline& pipeline, const Check& check) {
  std::vector<SceneObject> objects = ReadScene(in, spec.grid, pipeline);
  check();
  for (int s = 0; s < spec.later_steps; ++s) {
    for (SceneObject& object : objects) ReadChange(in, spec.grid, object, pipeline);
    check();
  }
}

/// The reference's answer to `request` (its method replaced by exact) on the scene as it stands.
inline StepResult ExpectedAnswer(Pipeline& pipeline, StepRequest request) {
  request.method = Method::kExact;
  Result<StepResult> expected = pipeline.Step(request);
  FAR_FUZZ_CHECK(expected.ok());
  return std::move(*expected);
}

// Prints the pairs one list holds and the other does not, before a failed check aborts: a
// finding then says which triangles the method missed or added.
inline void PrintDifference(const char* what, std::vector<ContactPair> found,
                            std::vector<ContactPair> expected) {
  std::sort(found.begin(), found.end());
  std::sort(expected.begin(), expected.end());
  std::vector<ContactPair> missed, extra;
  std::set_difference(expected.begin(), expected.end(), found.begin(), found.end(),
                      std::back_inserter(missed));
  std::set_difference(found.begin(), found.end(), expected.begin(), expected.end(),
                      std::back_inserter(extra));
  for (const auto& [list, name] : {std::pair{&missed, "missed"}, std::pair{&extra, "extra"}}) {
    for (const ContactPair& p : *list) {
      std::fprintf(stderr, "%s %s: object %u triangle %u, object %u triangle %u\n", what, name,
                   p.object_a, p.triangle_a, p.object_b, p.triangle_b);
    }
  }
}

/// `request` must succeed and answer what `expected` holds: the same contacts, and the same
/// triangle pairs within the distance.
inline void CheckAnswer(Pipeline& pipeline, const StepRequest& request,
                        const StepResult& expected) {
  const Result<StepResult> found = pipeline.Step(request);
  FAR_FUZZ_CHECK(found.ok());
  const std::vector<ContactPair> found_near = PairsOf(found->distance_pairs);
  const std::vector<ContactPair> expected_near = PairsOf(expected.distance_pairs);
  if (found->contacts != expected.contacts || found_near != expected_near) {
    std::fprintf(stderr, "method %s:\n", std::string(ToString(request.method)).c_str());
    PrintDifference("contact", found->contacts, expected.contacts);
    PrintDifference("distance pair", found_near, expected_near);
  }
  FAR_FUZZ_CHECK(found->contacts == expected.contacts);
  FAR_FUZZ_CHECK(found_near == expected_near);
}

/// The GL targets' run: a pipeline of its own on the process's current context, the scene and
/// its steps from the rest of the input, each step's `request` held to `exact`.
inline void StepOnGlAgainstExact(FuzzInput& in, const SceneSpec& spec, const StepRequest& request) {
  PipelineOptions options;
  options.use_current_context = true;
  options.num_threads = 2;
  auto pipeline = Pipeline::Create(options);
  FAR_FUZZ_CHECK(pipeline.ok());
  StepScene(in, spec, **pipeline,
            [&] { CheckAnswer(**pipeline, request, ExpectedAnswer(**pipeline, request)); });
}

}  // namespace far::fuzz
