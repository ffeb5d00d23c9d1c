// "breaking": a vase rolls down a bowl-shaped terrain into a rock, breaks, and its fragments
// slide apart.

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "mesh_tools.h"

#include "far/scenes/scenes.h"

namespace far::scenes {
namespace {

using internal::HeightField;
using internal::RestOn;

constexpr double kHalfSide = 8.0;     // terrain: [-8, 8]^2 metres
constexpr double kVaseHeight = 1.6;   // along the vase's axis (its z)
constexpr double kRollRadius = 0.45;  // about its belly's radius: how far one radian rolls
const Eigen::Vector2d kRock(1.2, 0.3);

double TerrainHeight(double x, double y) {
  const double rock = (Eigen::Vector2d(x, y) - kRock).squaredNorm();
  return 0.035 * (x * x + y * y) + 0.12 * std::sin(0.9 * x + 0.3) * std::sin(0.8 * y) +
         0.05 * std::sin(2.3 * x + 1.7 * y) + 0.45 * std::exp(-rock / 0.25);
}

// The vase's outline: radius at s in (0, 1) from its base to its lip.
double VaseRadius(double s) {
  if (s < 0.8) {
    const double belly = std::sin(std::numbers::pi * s / 0.8);
    return 0.2 + 0.3 * belly * belly;
  }
  return 0.2 + 0.08 * std::sin(0.5 * std::numbers::pi * (s - 0.8) / 0.2);
}

}  // namespace

Scene BreakingScene(uint64_t seed, int frames, int min_static_triangles, int min_rigid_triangles,
                    int num_fragments) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };
  num_fragments = std::max(1, num_fragments);

  // The terrain: 2 g^2 triangles.
  const int cells =
      std::max(2, static_cast<int>(std::ceil(std::sqrt(std::max(0, min_static_triangles) / 2.0))));
  const HeightField terrain(Eigen::Vector2d(-kHalfSide, -kHalfSide),
                            Eigen::Vector2d(kHalfSide, kHalfSide), cells, cells, TerrainHeight);
  SceneObject ground;
  ground.id = 1;
  ground.name = "terrain";
  ground.motion = Motion::kStatic;
  ground.mesh_path = "breaking_terrain.obj";
  ground.mesh = terrain.ToMesh();

  // The vase: `rings` rings of 2 * rings slices, 4 rings^2 triangles.
  const int rings =
      std::max(3, static_cast<int>(std::ceil(std::sqrt(std::max(0, min_rigid_triangles) / 4.0))));
  std::vector<Eigen::Vector2d> outline;
  for (int i = 1; i <= rings; ++i) {
    const double s = static_cast<double>(i) / (rings + 1);
    outline.emplace_back(VaseRadius(s), kVaseHeight * (s - 0.5));
  }
  SceneObject vase;
  vase.id = 2;
  vase.name = "vase";
  vase.motion = Motion::kRigid;
  vase.mesh_path = "breaking_vase.obj";
  vase.mesh = internal::LatheMesh(outline, -kVaseHeight / 2, kVaseHeight / 2, 2 * rings);
  const std::vector<Eigen::Vector3d> vase_p_OV = vase.mesh.p_MV;  // vase.mesh moves into the scene

  // Its path: lying on its side, rolling from the rim of the bowl into the rock.
  const Eigen::Vector2d start(-6.0 + uniform(-0.5, 0.5), -1.5 + uniform(-1.0, 1.0));
  const Eigen::Vector2d direction = (kRock - start).normalized();
  const Eigen::Vector2d end = kRock - 0.75 * direction;
  const Eigen::Vector3d roll_axis(-direction.y(), direction.x(), 0);  // up x direction
  const Eigen::Quaterniond lying =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), roll_axis);
  const double depth = uniform(0.02, 0.04);
  const int breaks_at = std::max(1, frames / 2);
  const auto vase_pose = [&](int f) {
    const double s = static_cast<double>(f) / breaks_at;
    const double travelled = (end - start).norm() * s * s;  // speeding up down the slope
    const double angle = travelled / kRollRadius;
    const Eigen::Quaterniond rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(0.08 * std::sin(3 * angle),
                                             Eigen::Vector3d(direction.x(), direction.y(), 0))) *
        Eigen::Quaterniond(Eigen::AngleAxisd(angle, roll_axis)) * lying;
    return RestOn(terrain, vase_p_OV, rotation, start + travelled * direction, depth);
  };
  vase.X_WO = vase_pose(0);

  // The fragments, and where each goes after the break.
  struct Flight {
    Pose X_WF;  // at the break
    Eigen::Vector2d direction;
    double distance, spin, depth;
    Eigen::Vector3d spin_axis;
  };
  std::vector<internal::Fragment> fragments =
      internal::Fracture(vase.mesh, num_fragments, Eigen::Vector3d::Zero(), &rng);
  const Pose X_WO_break = vase_pose(breaks_at);
  std::vector<Flight> flights;
  for (const internal::Fragment& fragment : fragments) {
    Flight flight;
    const Eigen::Vector3d p_WF = X_WO_break.translation + X_WO_break.rotation * fragment.p_OF;
    flight.X_WF = internal::MakePose(p_WF, X_WO_break.rotation);
    // Outwards from the vase's center, carried on along its way.
    Eigen::Vector2d out = (p_WF - X_WO_break.translation).head<2>();
    if (out.norm() < 1e-6) out = Eigen::Vector2d(uniform(-1, 1), uniform(-1, 1));
    flight.direction = (0.6 * out.normalized() + 0.4 * direction).normalized();
    flight.distance = uniform(1.5, 3.5);
    flight.spin = uniform(2.0, 6.0);
    flight.spin_axis = Eigen::Vector3d(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)).normalized();
    flight.depth = uniform(0.02, 0.04);
    flights.push_back(flight);
  }

  Scene scene;
  scene.objects.push_back(std::move(ground));
  const uint32_t vase_id = vase.id;
  scene.objects.push_back(std::move(vase));
  const int after = std::max(1, frames - 1 - breaks_at);
  for (int f = 1; f < frames; ++f) {
    FrameUpdate frame;
    if (f < breaks_at) {
      frame.poses.emplace_back(vase_id, vase_pose(f));
    } else if (f == breaks_at) {
      frame.removals.push_back(vase_id);
      for (size_t k = 0; k < fragments.size(); ++k) {
        SceneObject piece;
        piece.id = vase_id + 1 + static_cast<uint32_t>(k);
        piece.name = "vase-fragment-" + std::to_string(k + 1);
        piece.motion = Motion::kRigid;
        piece.mesh_path = "breaking_fragment_" + std::to_string(piece.id) + ".obj";
        piece.mesh = fragments[k].mesh;
        piece.X_WO = flights[k].X_WF;
        frame.additions.push_back(std::move(piece));
      }
    } else {
      const double u = static_cast<double>(f - breaks_at) / after;
      const double eased = 1 - (1 - u) * (1 - u);  // slowing down
      for (size_t k = 0; k < fragments.size(); ++k) {
        const Flight& flight = flights[k];
        const Eigen::Quaterniond rotation =
            internal::RotationVector(flight.spin * eased * flight.spin_axis) * flight.X_WF.rotation;
        const Eigen::Vector2d xy =
            flight.X_WF.translation.head<2>() + flight.distance * eased * flight.direction;
        frame.poses.emplace_back(
            vase_id + 1 + static_cast<uint32_t>(k),
            RestOn(terrain, fragments[k].mesh.p_MV, rotation, xy, flight.depth));
      }
    }
    scene.frames.push_back(std::move(frame));
  }
  return scene;
}

}  // namespace far::scenes
