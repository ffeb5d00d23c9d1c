#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "far/base/thread_pool.h"
#include "far/model/scene.h"
#include "far/pairs/exact_stage.h"
#include "far/pairs/world_object.h"
#include "far/scenes/scenes.h"

// Scene generators shared by the GPU tests and the studies in bench/. Every generator is
// deterministic for a seed.
namespace far::testing {

// The generators live in far/scenes.h; tests and studies use them through this namespace.
using scenes::LeavesScene;
using scenes::RandomSoup;
using scenes::SphereMesh;

/// The objects of `scene` placed in the world: vertices moved by each pose (and flushed, as
/// the pipeline places them: FlushTinyCoordinates). views[i] is objects[i], slot i.
struct WorldScene {
  std::vector<std::vector<Eigen::Vector3d>> p_WV;
  std::vector<WorldObjectView> views;
  std::vector<uint32_t> ids;  ///< by slot: objects[i].id
};
WorldScene PlaceInWorld(const std::vector<SceneObject>& objects);

/// The brute-force reference answer for `objects`, by id (as a step answers).
struct ReferencePairs {
  std::vector<ContactPair> contacts;
  std::vector<DistancePair> distance_pairs;
};
ReferencePairs ReferenceAnswer(const std::vector<SceneObject>& objects,
                               std::optional<double> distance, ThreadPool& pool);

/// `n` large triangles stacked above each other, each the half (0,0)-(1,0)-(0,1) of the unit
/// square, at z = z0, z0 + dz, ...: every GPU view of two such objects draws every piece over
/// half the viewport, so the views' cost is fill (seconds for a few hundred triangles at
/// 2048^2 on llvmpipe) while their setup (hierarchies, pieces) stays small.
Mesh StackedTriangles(int n, double z0, double dz);

/// Returns `objects` moved by the rigid transform X (applied to every pose).
std::vector<SceneObject> Transformed(std::vector<SceneObject> objects, const Eigen::Isometry3d& X);

}  // namespace far::testing
