#include "far/scenes/scenes.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "mesh_tools.h"

namespace far::scenes {

using internal::kFrameSeconds;

std::vector<SceneObject> RandomSoup(uint64_t seed, int num_objects, int triangles_per_object,
                                    double world_size, double triangle_size,
                                    const Eigen::Vector3d& origin) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-0.5, 0.5);
  auto random_vector = [&] { return Eigen::Vector3d(unit(rng), unit(rng), unit(rng)); };
  std::vector<SceneObject> objects;
  for (int o = 0; o < num_objects; ++o) {
    SceneObject object;
    object.id = static_cast<uint32_t>(o * 3 + 1);  // ids need not be contiguous
    object.name = "cluster-" + std::to_string(object.id);
    object.motion = Motion::kRigid;
    // Vertices in the object frame, around its origin; the pose places the cluster.
    const double cluster = triangle_size * std::cbrt(static_cast<double>(triangles_per_object));
    for (int t = 0; t < triangles_per_object; ++t) {
      const Eigen::Vector3d center = cluster * random_vector();
      for (int v = 0; v < 3; ++v)
        object.mesh.p_MV.push_back(center + triangle_size * random_vector());
      const auto base = static_cast<uint32_t>(3 * t);
      object.mesh.triangles.push_back({base, base + 1, base + 2});
    }
    object.X_WO.translation = origin + world_size * random_vector();
    // A uniformly random rotation from this generator (Eigen's UnitRandom uses std::rand, which
    // would make the scene depend on what else ran before).
    std::normal_distribution<double> normal;
    object.X_WO.rotation =
        Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng)).normalized();
    objects.push_back(std::move(object));
  }
  return objects;
}

Mesh BoxMesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  Mesh mesh;
  for (int k = 0; k < 8; ++k) {
    mesh.p_MV.emplace_back(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(),
                           k & 4 ? hi.z() : lo.z());
  }
  mesh.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                    {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return mesh;
}

Mesh SphereMesh(const Eigen::Vector3d& center, double radius, int stacks, int slices) {
  Mesh mesh;
  // Poles plus (stacks - 1) rings of `slices` vertices.
  mesh.p_MV.push_back(center + Eigen::Vector3d(0, 0, radius));
  for (int i = 1; i < stacks; ++i) {
    const double theta = std::numbers::pi * i / stacks;
    for (int j = 0; j < slices; ++j) {
      const double phi = 2 * std::numbers::pi * j / slices;
      mesh.p_MV.push_back(center + radius * Eigen::Vector3d(std::sin(theta) * std::cos(phi),
                                                            std::sin(theta) * std::sin(phi),
                                                            std::cos(theta)));
    }
  }
  mesh.p_MV.push_back(center + Eigen::Vector3d(0, 0, -radius));
  const auto ring = [&](int i, int j) {
    return static_cast<uint32_t>(1 + (i - 1) * slices + (j % slices));
  };
  const auto south = static_cast<uint32_t>(mesh.p_MV.size() - 1);
  for (int j = 0; j < slices; ++j) {
    mesh.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
    for (int i = 1; i < stacks - 1; ++i) {
      mesh.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      mesh.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
    mesh.triangles.push_back({ring(stacks - 1, j), south, ring(stacks - 1, j + 1)});
  }
  return mesh;
}

namespace {

// A closed tube (open cylinder with capped ends) from a to b, in `segments` rings' worth of
// lengthwise pieces (1: one quad per side from end to end).
void AppendTube(Mesh* mesh, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius,
                int sides, int segments) {
  const Eigen::Vector3d axis = (b - a).normalized();
  const Eigen::Vector3d u = axis.unitOrthogonal(), v = axis.cross(u);
  const auto base = static_cast<uint32_t>(mesh->p_MV.size());
  for (int k = 0; k <= segments; ++k) {
    const Eigen::Vector3d center = a + (b - a) * (static_cast<double>(k) / segments);
    for (int s = 0; s < sides; ++s) {
      const double phi = 2 * std::numbers::pi * s / sides;
      mesh->p_MV.push_back(center + radius * (std::cos(phi) * u + std::sin(phi) * v));
    }
  }
  const auto n = static_cast<uint32_t>(sides);
  for (uint32_t k = 0; k < static_cast<uint32_t>(segments); ++k) {
    const uint32_t ring = base + k * n;
    for (uint32_t s = 0; s < n; ++s) {
      const uint32_t s1 = (s + 1) % n;
      mesh->triangles.push_back({ring + s, ring + s1, ring + n + s1});
      mesh->triangles.push_back({ring + s, ring + n + s1, ring + n + s});
    }
  }
  const uint32_t last = base + static_cast<uint32_t>(segments) * n;
  for (uint32_t s = 1; s + 1 < n; ++s) {
    mesh->triangles.push_back({base, base + s + 1, base + s});
    mesh->triangles.push_back({last, last + s, last + s + 1});
  }
}

// The tree of LeavesScene: a trunk and 24 branches spiralling up, as closed tubes cut into
// pieces of about `piece_length` along their length (0: each tube in one piece).
Mesh TreeMesh(double piece_length) {
  const auto segments = [piece_length](double length) {
    return piece_length > 0 ? std::max(1, static_cast<int>(std::lround(length / piece_length))) : 1;
  };
  Mesh tree;
  AppendTube(&tree, {0, 0, 0}, {0, 0, 6}, 0.3, 16, segments(6.0));
  for (int b = 0; b < 24; ++b) {
    const double height = 2.0 + 4.0 * b / 24.0, angle = 2.4 * b;
    const Eigen::Vector3d start(0, 0, height);
    const Eigen::Vector3d end =
        start + Eigen::Vector3d(2.5 * std::cos(angle), 2.5 * std::sin(angle), 0.8);
    AppendTube(&tree, start, end, 0.08, 8, segments((end - start).norm()));
  }
  return tree;
}

}  // namespace

std::vector<SceneObject> LeavesScene(uint64_t seed, int num_leaves, int leaf_cells, double time) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<SceneObject> objects;
  // The tree: a trunk and branches spiralling up, as closed tubes; static.
  SceneObject tree;
  tree.id = 0;
  tree.name = "tree";
  tree.motion = Motion::kStatic;
  tree.mesh = TreeMesh(0);
  tree.mesh_path = "tree.obj";
  objects.push_back(std::move(tree));
  // Leaves: bent grids of leaf_cells x leaf_cells quads, falling and swirling with time.
  for (int l = 0; l < num_leaves; ++l) {
    const double radius = 3.0 * std::sqrt(unit(rng)), angle = 2 * std::numbers::pi * unit(rng);
    const double height = 1.0 + 6.0 * unit(rng), phase = 2 * std::numbers::pi * unit(rng);
    const double size = 0.25 + 0.1 * unit(rng);
    SceneObject leaf;
    leaf.id = static_cast<uint32_t>(l + 1);
    leaf.name = "leaf-" + std::to_string(leaf.id);
    leaf.motion = Motion::kDeformable;
    leaf.mesh_path = "leaf_" + std::to_string(leaf.id) + ".obj";
    const double fall = std::fmod(height - 0.4 * time + 8.0, 8.0) - 0.5;
    const double swirl = angle + 0.3 * time;
    const Eigen::Vector3d center(radius * std::cos(swirl), radius * std::sin(swirl), fall);
    const double bend = 0.3 * std::sin(phase + 2.0 * time);
    const Eigen::Matrix3d tilt =
        (Eigen::AngleAxisd(phase, Eigen::Vector3d::UnitZ()) *
         Eigen::AngleAxisd(0.7 * std::sin(phase + time), Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
    for (int i = 0; i <= leaf_cells; ++i) {
      for (int j = 0; j <= leaf_cells; ++j) {
        const double x = size * (static_cast<double>(i) / leaf_cells - 0.5);
        const double y = size * (static_cast<double>(j) / leaf_cells - 0.5);
        leaf.mesh.p_MV.push_back(center +
                                 tilt * Eigen::Vector3d(x, y, bend * (x * x + y * y) / size));
      }
    }
    const auto index = [&](int i, int j) {
      return static_cast<uint32_t>(i * (leaf_cells + 1) + j);
    };
    for (int i = 0; i < leaf_cells; ++i) {
      for (int j = 0; j < leaf_cells; ++j) {
        leaf.mesh.triangles.push_back({index(i, j), index(i + 1, j), index(i + 1, j + 1)});
        leaf.mesh.triangles.push_back({index(i, j), index(i + 1, j + 1), index(i, j + 1)});
      }
    }
    objects.push_back(std::move(leaf));
  }
  return objects;
}

Scene AnimatedLeavesScene(uint64_t seed, int num_leaves, int leaf_cells, int frames) {
  Scene scene;
  scene.objects = LeavesScene(seed, num_leaves, leaf_cells, 0.0);
  // The same tree cut into short pieces along its tubes, so that the triangles a contact marks
  // (far-snapshot, far-client play --contacts) are near the contact, not a whole trunk's length.
  scene.objects[0].mesh = TreeMesh(0.3);
  const uint32_t vase_id = static_cast<uint32_t>(num_leaves + 1);
  SceneObject vase;
  vase.id = vase_id;
  vase.name = "vase";
  vase.motion = Motion::kRigid;
  vase.mesh_path = "vase.obj";
  vase.mesh = SphereMesh(Eigen::Vector3d::Zero(), 0.5, 8, 16);
  vase.X_WO.translation = Eigen::Vector3d(1.2, 0.0, 3.0);
  scene.objects.push_back(vase);
  const int breaks_at = std::max(1, frames / 3);
  const int num_fragments = 4;
  for (int f = 1; f < frames; ++f) {
    FrameUpdate frame;
    // Leaves: new vertices (same triangles).
    const auto leaves = LeavesScene(seed, num_leaves, leaf_cells, kFrameSeconds * f);
    for (size_t l = 1; l < leaves.size(); ++l)
      frame.vertices.emplace_back(leaves[l].id, leaves[l].mesh);
    if (f < breaks_at) {
      // The vase falls towards the trunk's base.
      Pose pose;
      pose.translation = Eigen::Vector3d(1.2 - 0.9 * f / breaks_at, 0.0, 3.0 - 2.4 * f / breaks_at);
      frame.poses.emplace_back(vase_id, pose);
    } else if (f == breaks_at) {
      // It breaks: removed, and fragments appear where it was.
      frame.removals.push_back(vase_id);
      for (int k = 0; k < num_fragments; ++k) {
        SceneObject fragment;
        fragment.id = vase_id + 1 + static_cast<uint32_t>(k);
        fragment.name = "vase-fragment-" + std::to_string(k + 1);
        fragment.motion = Motion::kRigid;
        fragment.mesh_path = "fragment.obj";
        fragment.mesh = SphereMesh(Eigen::Vector3d::Zero(), 0.22, 6, 10);
        const double angle = std::numbers::pi / 2 * k;
        fragment.X_WO.translation =
            Eigen::Vector3d(0.3 + 0.3 * std::cos(angle), 0.3 * std::sin(angle), 0.6);
        frame.additions.push_back(fragment);
      }
    } else {
      // Fragments fly apart.
      const double t = kFrameSeconds * (f - breaks_at);
      for (int k = 0; k < num_fragments; ++k) {
        const double angle = std::numbers::pi / 2 * k;
        Pose pose;
        pose.translation = Eigen::Vector3d(0.3 + (0.3 + 0.8 * t) * std::cos(angle),
                                           (0.3 + 0.8 * t) * std::sin(angle),
                                           std::max(0.2, 0.6 + 0.5 * t - 1.2 * t * t));
        pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(3 * t + k, Eigen::Vector3d::UnitZ()));
        frame.poses.emplace_back(vase_id + 1 + static_cast<uint32_t>(k), pose);
      }
    }
    scene.frames.push_back(std::move(frame));
  }
  return scene;
}

}  // namespace far::scenes
