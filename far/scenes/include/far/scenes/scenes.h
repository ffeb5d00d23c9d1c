#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "far/model/scene.h"

// Deterministic scene generators for demos, tests and studies.
namespace far::scenes {

/// Random triangle soup: `num_objects` rigid clusters of `triangles_per_object` random
/// triangles (edge length about `triangle_size`), cluster centers uniform in a cube of side
/// `world_size` centered at `origin`. Ids 1, 4, 7, ... (not contiguous on purpose).
std::vector<SceneObject> RandomSoup(uint64_t seed, int num_objects, int triangles_per_object,
                                    double world_size, double triangle_size,
                                    const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

/// A closed UV sphere of radius `radius` at `center` (2 * slices * (stacks - 1) triangles).
Mesh SphereMesh(const Eigen::Vector3d& center, double radius, int stacks, int slices);

/// A tree-with-falling-leaves-like scene: one static "tree" (id 0: trunk and branches as
/// closed tubes) and `num_leaves` small deformable leaves (ids 1..num_leaves, bent grids of
/// 2 * leaf_cells^2 triangles) around it. `time` moves the leaves down and bends them.
std::vector<SceneObject> LeavesScene(uint64_t seed, int num_leaves, int leaf_cells, double time);

/// An animated demo scene: the leaves scene over `frames` steps (vertex updates), plus a
/// rigid "vase" that falls onto the tree's base and breaks into fragments (removal and
/// additions) at frame frames / 3; the fragments fly apart (poses).
Scene AnimatedLeavesScene(uint64_t seed, int num_leaves, int leaf_cells, int frames);

}  // namespace far::scenes
