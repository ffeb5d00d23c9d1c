// "bunnies": two refined copies of a mesh, one static, one moving rigidly through it.

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "mesh_tools.h"

#include "far/scenes/scenes.h"

namespace far::scenes {

using internal::kFrameSeconds;

Scene BunniesScene(const Mesh& bunny, int subdivision, uint64_t seed, int frames) {
  constexpr double kPeriod = 6.0;  // seconds per pass there and back
  subdivision = std::max(1, subdivision);
  Mesh mesh = RefineMesh(bunny, subdivision);
  // Centered on its box, so that the path below is in units of the mesh's size.
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : mesh.p_MV) box.extend(p);
  const Eigen::Vector3d center = box.center();
  for (Eigen::Vector3d& p : mesh.p_MV) p -= center;
  const double size = box.sizes().maxCoeff();

  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double phase = kPeriod * unit(rng);
  const Eigen::Vector3d axis =
      Eigen::Vector3d(0.3 + 0.2 * unit(rng), 1.0, 0.2 + 0.2 * unit(rng)).normalized();
  const double omega = 2 * std::numbers::pi / kPeriod;
  const auto pose = [&](int f) {
    const double t = kFrameSeconds * f + phase;
    const Eigen::Vector3d p_WO =
        size * Eigen::Vector3d(0.22 * std::cos(omega * t), 0.07 * std::sin(2 * omega * t) + 0.03,
                               0.06 + 0.04 * std::sin(omega * t + 1.0));
    // Never the identity: two copies in the same place would be all coplanar pairs.
    const double angle = 0.45 + 0.3 * std::sin(omega * t);
    return internal::MakePose(p_WO, Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis)));
  };

  Scene scene;
  const std::string mesh_path = "bunnies_bunny_n" + std::to_string(subdivision) + ".obj";
  SceneObject still;
  still.id = 1;
  still.name = "bunny-still";
  still.motion = Motion::kStatic;
  still.mesh_path = mesh_path;
  still.mesh = mesh;
  SceneObject moving;
  moving.id = 2;
  moving.name = "bunny-moving";
  moving.motion = Motion::kRigid;
  moving.mesh_path = mesh_path;  // the same mesh: written once
  moving.mesh = std::move(mesh);
  moving.X_WO = pose(0);
  scene.objects.push_back(std::move(still));
  scene.objects.push_back(std::move(moving));
  for (int f = 1; f < frames; ++f) {
    FrameUpdate frame;
    frame.poses.emplace_back(2, pose(f));
    scene.frames.push_back(std::move(frame));
  }
  return scene;
}

}  // namespace far::scenes
