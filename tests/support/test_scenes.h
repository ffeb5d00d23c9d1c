#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "far/model/scene.h"
#include "far/pairs/exact_stage.h"
#include "far/pairs/thread_pool.h"
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
/// the pipeline places them: FlushTinyCoordinates).
struct WorldScene {
  std::vector<std::vector<Eigen::Vector3d>> p_WV;
  std::vector<WorldObjectView> views;
};
WorldScene PlaceInWorld(const std::vector<SceneObject>& objects);

/// The brute-force reference answer for `objects`.
ExactResult ReferenceAnswer(const std::vector<SceneObject>& objects, std::optional<double> distance,
                            ThreadPool& pool);

/// Returns `objects` moved by the rigid transform X (applied to every pose).
std::vector<SceneObject> Transformed(std::vector<SceneObject> objects, const Eigen::Isometry3d& X);

}  // namespace far::testing
