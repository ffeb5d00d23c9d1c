// "leaves": a static tree and deformable leaves that hang in pairs, sway, come off and fall.

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "mesh_tools.h"

#include "far/scenes/scenes.h"

namespace far::scenes {
namespace {

using internal::AppendTube;
using internal::kFrameSeconds;
using internal::Random;
using internal::TubeTriangles;

constexpr double kCycle = 8.0;  // seconds from growing on the branch to growing back
constexpr int kBranches = 24, kTwigsPerBranch = 2;

// Tube resolutions of the tree at detail k.
struct TreeDetail {
  int trunk_sides, trunk_segments, branch_sides, branch_segments, twig_sides, twig_segments;
  explicit TreeDetail(int k)
      : trunk_sides(2 * k),
        trunk_segments(3 * k),
        branch_sides(k),
        branch_segments(k),
        twig_sides(std::max(4, k / 2)),
        twig_segments(std::max(2, k / 2)) {}
  int Triangles() const {
    return TubeTriangles(trunk_sides, trunk_segments) +
           kBranches * TubeTriangles(branch_sides, branch_segments) +
           kBranches * kTwigsPerBranch * TubeTriangles(twig_sides, twig_segments);
  }
};

struct Segment {
  Eigen::Vector3d a, b;
};

struct Leaf {
  Eigen::Vector3d p_WS;  // stem point while hanging: on a branch or twig axis
  double yaw, pitch, length, width;
  double phase, hang;  // cycle phase (shared by a pair) and seconds spent hanging
  double sway[3];      // phases
  Eigen::Vector2d drift_dir;
  double drift, fall_speed, flutter, spin;
  Eigen::Vector3d spin_axis;
};

Eigen::Matrix3d HangRotation(const Leaf& leaf, double t) {
  return (Eigen::AngleAxisd(leaf.yaw + 0.15 * std::sin(0.9 * t + leaf.sway[1]),
                            Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(leaf.pitch + 0.2 * std::sin(1.7 * t + leaf.sway[2]),
                            Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(0.3 * std::sin(1.3 * t + leaf.sway[1]), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// The leaf's vertices in the world at time t (the leaf's mesh frame is the world frame).
std::vector<Eigen::Vector3d> LeafVertices(const Leaf& leaf, int cells, double t) {
  const double cycle = std::fmod(t + leaf.phase, kCycle);
  const bool hanging = cycle < leaf.hang;
  const double fall_time = hanging ? 0.0 : cycle - leaf.hang;
  const double detached_at = t - fall_time;
  const double bend = hanging ? 0.25 + 0.15 * std::sin(2.1 * t + leaf.sway[0])
                              : 0.3 + 0.25 * std::sin(4.0 * fall_time + leaf.sway[0]);
  Eigen::Matrix3d R = HangRotation(leaf, detached_at);
  Eigen::Vector3d p_WS = leaf.p_WS;
  if (!hanging) {
    R = internal::RotationVector(leaf.spin * fall_time * leaf.spin_axis).toRotationMatrix() * R;
    const Eigen::Vector2d side(-leaf.drift_dir.y(), leaf.drift_dir.x());
    const Eigen::Vector2d xy =
        leaf.drift * fall_time * leaf.drift_dir +
        leaf.flutter * (std::sin(2.5 * fall_time + leaf.sway[2]) - std::sin(leaf.sway[2])) * side;
    p_WS += Eigen::Vector3d(xy.x(), xy.y(), -leaf.fall_speed * fall_time);
  }
  std::vector<Eigen::Vector3d> p_WV;
  p_WV.reserve(static_cast<size_t>((cells + 1) * (cells + 1)));
  for (int i = 0; i <= cells; ++i) {
    const double s = static_cast<double>(i) / cells;
    // The stem point (x = 0, y = 0) is inside the grid, not on its border, so that a pair's
    // leaves cross there rather than touch at a corner.
    const double x = leaf.length * (s - 0.12);
    const double half_width = 0.5 * leaf.width * (0.35 + 0.65 * std::sin(std::numbers::pi * s));
    for (int j = 0; j <= cells; ++j) {
      const double y = half_width * (2.0 * j / cells - 1.0);
      const double z = bend * x * x / leaf.length + 0.15 * y * y / leaf.width;
      p_WV.push_back(p_WS + R * Eigen::Vector3d(x, y, z));
    }
  }
  return p_WV;
}

// The tree at the coarsest detail with enough triangles.
TreeDetail CoarsestDetail(int min_tree_triangles) {
  int k = 4;
  while (TreeDetail(k).Triangles() < min_tree_triangles && k < 400) ++k;
  return TreeDetail(k);
}

// The tree (id 0): a trunk, then branch by branch a branch and its twigs, each branch drawing its
// angle and elevation in that order. Adds to `perches` where leaves may hang on each.
SceneObject Tree(const TreeDetail& detail, Random* random, std::vector<Segment>* perches) {
  SceneObject tree;
  tree.id = 0;
  tree.name = "tree";
  tree.motion = Motion::kStatic;
  tree.mesh_path = "leaves_tree.obj";
  AppendTube(&tree.mesh, {0, 0, 0}, {0, 0, 7.0}, 0.35, 0.18, detail.trunk_sides,
             detail.trunk_segments);
  for (int b = 0; b < kBranches; ++b) {
    const double height = 2.2 + 4.4 * b / (kBranches - 1);
    const double angle = 2.4 * b + random->Uniform(-0.2, 0.2),
                 elevation = random->Uniform(0.25, 0.45);
    const double length = 2.6 - 1.0 * b / (kBranches - 1);
    const Eigen::Vector3d direction(std::cos(angle) * std::cos(elevation),
                                    std::sin(angle) * std::cos(elevation), std::sin(elevation));
    const Eigen::Vector3d start(0, 0, height), end = start + length * direction;
    AppendTube(&tree.mesh, start, end, 0.09, 0.04, detail.branch_sides, detail.branch_segments);
    perches->push_back({start + 0.3 * (end - start), end});
    for (int w = 0; w < kTwigsPerBranch; ++w) {
      const Eigen::Vector3d root = start + (w == 0 ? 0.5 : 0.85) * (end - start);
      const double twig_angle = angle + (w == 0 ? 0.8 : -0.8);
      const Eigen::Vector3d twig_direction =
          Eigen::Vector3d(std::cos(twig_angle), std::sin(twig_angle), 0.6).normalized();
      const Eigen::Vector3d tip = root + 0.9 * twig_direction;
      AppendTube(&tree.mesh, root, tip, 0.035, 0.018, detail.twig_sides, detail.twig_segments);
      perches->push_back({root + 0.2 * (tip - root), tip});
    }
  }
  return tree;
}

// Where leaf l hangs: a first leaf of a pair on a random perch, the second at the first's stem
// point and phase, turned across it.
void PlaceLeaf(std::vector<Leaf>* leaves, int l, const std::vector<Segment>& perches,
               Random* random) {
  Leaf& leaf = (*leaves)[static_cast<size_t>(l)];
  if (l % 2 == 1) {
    const Leaf& first = (*leaves)[static_cast<size_t>(l - 1)];
    leaf.p_WS = first.p_WS;
    leaf.phase = first.phase;
    leaf.yaw = first.yaw + random->Uniform(1.2, 1.9);  // across the first leaf
  } else {
    const Segment& perch = perches[static_cast<size_t>(random->Unit() * perches.size())];
    leaf.p_WS = perch.a + random->Unit() * (perch.b - perch.a);
    leaf.phase = random->Uniform(0.0, kCycle);
    const Eigen::Vector3d out = perch.b - perch.a;
    leaf.yaw = std::atan2(out.y(), out.x()) + random->Uniform(-0.6, 0.6);
  }
}

// The rest of a leaf: its shape, how it sways, and how it falls.
void DrawShapeAndMotion(Leaf* leaf, Random* random) {
  leaf->pitch = random->Uniform(0.5, 1.2);
  leaf->length = random->Uniform(0.32, 0.42);
  leaf->width = 0.55 * leaf->length;
  leaf->hang = random->Uniform(0.5, 0.8) * kCycle;
  for (double& phase : leaf->sway) phase = random->Uniform(0.0, 2 * std::numbers::pi);
  const double drift_angle = random->Uniform(0.0, 2 * std::numbers::pi);
  leaf->drift_dir = Eigen::Vector2d(std::cos(drift_angle), std::sin(drift_angle));
  leaf->drift = random->Uniform(0.3, 0.6);
  leaf->fall_speed = random->Uniform(0.7, 1.0);
  leaf->flutter = random->Uniform(0.2, 0.4);
  leaf->spin = random->Uniform(1.5, 3.0);
  leaf->spin_axis =
      Eigen::Vector3d(random->Uniform(-1, 1), random->Uniform(-1, 1), random->Uniform(-1, 1))
          .normalized();
}

// Leaves, in pairs that share a stem point and a cycle phase; all the draws of one leaf before
// the next's.
std::vector<Leaf> Leaves(int num_leaves, const std::vector<Segment>& perches, Random* random) {
  std::vector<Leaf> leaves(static_cast<size_t>(num_leaves));
  for (int l = 0; l < num_leaves; ++l) {
    PlaceLeaf(&leaves, l, perches, random);
    DrawShapeAndMotion(&leaves[static_cast<size_t>(l)], random);
  }
  return leaves;
}

SceneObject LeafObject(const Leaf& leaf, uint32_t id, int cells,
                       const std::vector<TriangleIndices>& triangles) {
  SceneObject object;
  object.id = id;
  object.name = "leaf-" + std::to_string(object.id);
  object.motion = Motion::kDeformable;
  object.mesh_path = "leaves_leaf_" + std::to_string(object.id) + ".obj";
  object.mesh.p_MV = LeafVertices(leaf, cells, 0.0);
  object.mesh.triangles = triangles;
  return object;
}

// The update at time t: every leaf's vertices (ids 1..num_leaves).
FrameUpdate Frame(const std::vector<Leaf>& leaves, int cells,
                  const std::vector<TriangleIndices>& triangles, double t) {
  FrameUpdate frame;
  frame.vertices.reserve(leaves.size());
  for (size_t l = 0; l < leaves.size(); ++l) {
    frame.vertices.push_back(internal::VertexUpdate(static_cast<uint32_t>(l + 1),
                                                    LeafVertices(leaves[l], cells, t), triangles));
  }
  return frame;
}

}  // namespace

Scene PaperLeavesScene(uint64_t seed, int frames, int num_leaves, int leaf_cells,
                       int min_tree_triangles) {
  leaf_cells = std::max(1, leaf_cells);
  num_leaves = std::max(0, num_leaves);
  Random random(seed);
  // The draws, in the scene's order: the branches, then the leaves.
  std::vector<Segment> perches;  // where leaves hang: branches and twigs
  SceneObject tree = Tree(CoarsestDetail(min_tree_triangles), &random, &perches);
  const std::vector<Leaf> leaves = Leaves(num_leaves, perches, &random);

  Scene scene;
  scene.objects.push_back(std::move(tree));
  const std::vector<TriangleIndices> triangles = internal::GridTriangles(leaf_cells);
  for (int l = 0; l < num_leaves; ++l) {
    scene.objects.push_back(LeafObject(leaves[static_cast<size_t>(l)], static_cast<uint32_t>(l + 1),
                                       leaf_cells, triangles));
  }
  for (int f = 1; f < frames; ++f) {
    scene.frames.push_back(Frame(leaves, leaf_cells, triangles, kFrameSeconds * f));
  }
  return scene;
}

}  // namespace far::scenes
