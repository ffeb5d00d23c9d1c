#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "far/exact_stage.h"
#include "far/scene.h"
#include "far/thread_pool.h"

// Scene generators shared by the GPU tests and the studies in bench/. Every generator is
// deterministic for a seed.
namespace far::testing {

/// Random triangle soup: `num_objects` clusters of `triangles_per_object` random triangles
/// (edge length about `triangle_size`), cluster centers uniform in a cube of side `world_size`
/// centered at `origin`.
std::vector<SceneObject> RandomSoup(uint64_t seed, int num_objects, int triangles_per_object,
                                    double world_size, double triangle_size,
                                    const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

/// A closed UV sphere of radius `radius` at `center` (2 * stacks * slices triangles).
Mesh SphereMesh(const Eigen::Vector3d& center, double radius, int stacks, int slices);

/// A tree-with-falling-leaves-like scene: one static "tree" (trunk and branches as closed
/// tubes) and `num_leaves` small deformable leaves (bent quads, 2 * leaf_cells^2 triangles)
/// around it. `time` moves the leaves down and bends them, as a simulation would.
std::vector<SceneObject> LeavesScene(uint64_t seed, int num_leaves, int leaf_cells, double time);

/// The objects of `scene` placed in the world: vertices moved by each pose.
struct WorldScene {
  std::vector<std::vector<Eigen::Vector3d>> p_WV;
  std::vector<WorldObjectView> views;
};
WorldScene PlaceInWorld(const std::vector<SceneObject>& objects);

/// The brute-force reference answer for `objects`.
ExactResult ReferenceAnswer(const std::vector<SceneObject>& objects,
                            std::optional<double> distance, ThreadPool& pool);

/// Returns `objects` moved by the rigid transform X (applied to every pose).
std::vector<SceneObject> Transformed(std::vector<SceneObject> objects, const Eigen::Isometry3d& X);

}  // namespace far::testing
