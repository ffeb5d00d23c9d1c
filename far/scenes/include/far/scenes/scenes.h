#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "far/model/scene.h"

// Deterministic scene generators for demos, tests and studies. Every object they make has a
// name (SceneObject::name) that says what it is, for contact listings and pictures: "tree",
// "leaf-<id>", "vase", "vase-fragment-<k>" (k from 1; a broken vase's pieces), "terrain",
// "bunny-still", "bunny-moving", "ground", "rolling-sphere-<tile>", "falling-sphere-<tile>",
// "cloth-<tile>" (tiles from 1), "cluster-<id>" (RandomSoup).
namespace far::scenes {

/// Random triangle soup: `num_objects` rigid clusters of `triangles_per_object` random
/// triangles (edge length about `triangle_size`), cluster centers uniform in a cube of side
/// `world_size` centered at `origin`. Ids 1, 4, 7, ... (not contiguous on purpose).
std::vector<SceneObject> RandomSoup(uint64_t seed, int num_objects, int triangles_per_object,
                                    double world_size, double triangle_size,
                                    const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

/// A closed axis-aligned box [lo, hi]: 8 vertices (vertex k has hi's x when bit 0 of k is set,
/// y for bit 1, z for bit 2) and 12 triangles, counterclockwise seen from outside.
Mesh BoxMesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);

/// A closed UV sphere of radius `radius` at `center` (2 * slices * (stacks - 1) triangles).
Mesh SphereMesh(const Eigen::Vector3d& center, double radius, int stacks, int slices);

/// A tree-with-falling-leaves-like scene: one static "tree" (id 0: trunk and branches as
/// closed tubes) and `num_leaves` small deformable leaves (ids 1..num_leaves, bent grids of
/// 2 * leaf_cells^2 triangles) around it. `time` moves the leaves down and bends them.
std::vector<SceneObject> LeavesScene(uint64_t seed, int num_leaves, int leaf_cells, double time);

/// An animated demo scene: the leaves scene over `frames` steps (vertex updates), plus a
/// rigid "vase" that falls onto the tree's base and breaks into fragments (removal and
/// additions) at frame frames / 3; the fragments fly apart (poses). The tree is LeavesScene's
/// with its tubes cut into pieces about 0.3 long (4,412 triangles instead of 732), so that the
/// triangles a contact involves are near it.
Scene AnimatedLeavesScene(uint64_t seed, int num_leaves, int leaf_cells, int frames);

/// Splits every edge of `mesh` into `n` equal parts and every triangle into n^2 triangles (a
/// lattice in the triangle's plane: the surface does not move, orientation is kept). Points on
/// an edge are shared by both of its triangles, so a closed mesh stays closed. Vertices:
/// V + E (n - 1) + F (n - 1)(n - 2) / 2. n <= 1 returns `mesh`.
Mesh RefineMesh(const Mesh& mesh, int n);

// The paper's workloads. Each returns a scene of `frames` frames (frames >= 1): frame 0 is
// `objects`, and `frames` holds frames - 1 updates (as AnimatedLeavesScene), each with only the
// kinds of update the workload calls for. Sizes are parameters with the paper's scale as
// default, so that a study can ask for a size. Every object has a mesh_path "<kind>_<what>.obj",
// one per distinct mesh, so that WriteScene can write the scene; vertex updates leave
// vertex_mesh_paths empty. Same arguments, same scene (the random numbers come from `seed` alone).
// Contacts (exactly intersecting triangle pairs of different objects) exist at most frames: the
// workloads are built so that culling has something to find.

/// "leaves", after the paper's falling leaves (section 5.1, figure 1). Id 0: a static tree, a
/// trunk, 24 branches and 48 twigs as closed tubes, with the smallest tessellation that has at
/// least `min_tree_triangles` triangles (default: 23,104). Ids 1..num_leaves: deformable leaves,
/// bent grids of leaf_cells^2 quads (2 leaf_cells^2 triangles, default 128) that hang in pairs
/// from a twig or branch, swaying and bending, then come off one by one and fall fluttering,
/// tumbling and curling, and grow back at their branch (a cycle of 8 s, 0.1 s per frame, each
/// pair at its own phase). Every frame updates the vertices of every leaf (no poses). Contacts:
/// a hanging leaf's stem point lies on its branch's axis, inside the tube, while the leaf reaches
/// out of it, so it crosses the branch's surface; the two leaves of a pair share that point
/// inside both grids at different angles, so they cross each other; about two thirds of the
/// leaves hang at any frame. Leaves have the identity pose (vertices in the world frame); there
/// is no ground: a falling leaf falls out of the tree until it grows back. Defaults: 151
/// objects, 42,304 triangles (tree 23,104, leaves 150 x 128).
Scene PaperLeavesScene(uint64_t seed, int frames, int num_leaves = 150, int leaf_cells = 8,
                       int min_tree_triangles = 22000);

/// "breaking": id 1, a static bowl-shaped terrain with bumps and a rock (a height field of at
/// least `min_static_triangles` triangles, default 100,352); id 2, a rigid closed vase of at
/// least `min_rigid_triangles` triangles (default 35,344) lying on its side, rolling down the
/// slope into the rock (poses). At frame max(1, frames / 2) the vase breaks: it is removed and
/// `num_fragments` rigid fragments (ids 3..2 + num_fragments) are added where it was (the vase's
/// triangles split by the Voronoi cells of random seed triangles, each piece closed by a fan to
/// an inner apex, in its own frame); afterwards they slide apart across the terrain, tumbling
/// (poses only). Frames >= 3 for poses before and after the break. The terrain is 16 x 16
/// units, the vase 1.6 long. Contacts: the vase and every fragment are placed so that their
/// lowest vertex is 0.02-0.04 under the terrain (the terrain's triangulated height, so exactly),
/// which makes each cross the ground at every frame; at the break the fragments also touch each
/// other. Defaults: 2 objects and 135,696 triangles until the break, then 13 objects.
Scene BreakingScene(uint64_t seed, int frames, int min_static_triangles = 100000,
                    int min_rigid_triangles = 35000, int num_fragments = 12);

/// "bunnies", the paper's figure 7: `bunny` (any closed mesh; the Stanford bunny in
/// bench/data/bunny.obj) refined by RefineMesh(bunny, subdivision) (n = 5: 25 x 3,674 = 91,850
/// triangles for the bunny) and centered on its bounding box. Id 1 is static at the identity;
/// id 2, the same mesh, is rigid and moves through it, back and forth along x by up to 22% of the
/// mesh's size with a wobble in y and z, while turning by 0.15-0.75 rad about a tilted axis
/// (poses only; a period of 60 frames at 0.1 s per frame, its phase and the axis's tilt from
/// `seed`). For the bunny: deep interpenetration at every frame (hundreds of intersecting
/// triangle pairs even unrefined); never the identical pose (the rotation is never zero).
/// Both objects use the one mesh file "bunnies_bunny_n<subdivision>.obj".
Scene BunniesScene(const Mesh& bunny, int subdivision, uint64_t seed, int frames);

/// "scaling": one family from about 5,000 to 300,000 triangles, for curves of time against
/// size. With s = sqrt(target_triangles / 5000), round(2 s) tiles of 4 x 4 units (at least one),
/// each with one cloth and two spheres: about 30% of the triangles in a static wavy ground (id 1)
/// under all tiles, 40% in rigid spheres (ids 2 + 2 i rolling, 3 + 2 i falling for tile i) and 30%
/// in deformable cloths (ids 2 + 2 tiles + i, identity pose, vertices in the world frame);
/// the number of objects and their resolution both grow as s, so every size looks alike. In
/// each tile one sphere rolls on a circle (poses) and the other falls from its own height and
/// rolls on after landing (poses); the cloth falls from its own height and settles over the
/// ground and over the rolling sphere, with waves moving through it (vertices every frame). 0.1 s
/// per frame. The total is within 2% of target_triangles (targets under 1,000 count as 1,000),
/// e.g. 5K: 7 objects, 20K: 13, 100K: 28, 300K: 46. Contacts: every sphere on the ground has
/// its lowest vertex under the terrain (so the rolling sphere touches the ground at every
/// frame), and a landed cloth's waves cross the ground and the sphere.
Scene ScalingScene(uint64_t seed, int target_triangles, int frames);

}  // namespace far::scenes
