// "breaking": a vase rolls down a bowl-shaped terrain into a rock, breaks, and its fragments
// slide apart.

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "mesh_tools.h"

#include "far/scenes/scenes.h"

namespace far::scenes {
namespace {

using internal::Fragment;
using internal::HeightField;
using internal::Random;
using internal::RestOn;

constexpr double kHalfSide = 8.0;     // terrain: [-8, 8]^2 metres
constexpr double kVaseHeight = 1.6;   // along the vase's axis (its z)
constexpr double kRollRadius = 0.45;  // about its belly's radius: how far one radian rolls
constexpr uint32_t kTerrainId = 1, kVaseId = 2;  // the fragments follow: kVaseId + 1 + k
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

// The terrain: 2 cells^2 triangles, the fewest that reach min_static_triangles.
HeightField Terrain(int min_static_triangles) {
  const int cells =
      std::max(2, static_cast<int>(std::ceil(std::sqrt(std::max(0, min_static_triangles) / 2.0))));
  return {Eigen::Vector2d(-kHalfSide, -kHalfSide), Eigen::Vector2d(kHalfSide, kHalfSide), cells,
          cells, TerrainHeight};
}

SceneObject TerrainObject(const HeightField& terrain) {
  SceneObject ground;
  ground.id = kTerrainId;
  ground.name = "terrain";
  ground.motion = Motion::kStatic;
  ground.mesh_path = "breaking_terrain.obj";
  ground.mesh = terrain.ToMesh();
  return ground;
}

// The vase, in its own frame with its axis along z (posed later): `rings` rings of 2 * rings
// slices, 4 rings^2 triangles, the fewest that reach min_rigid_triangles.
SceneObject Vase(int min_rigid_triangles) {
  const int rings =
      std::max(3, static_cast<int>(std::ceil(std::sqrt(std::max(0, min_rigid_triangles) / 4.0))));
  std::vector<Eigen::Vector2d> outline;
  for (int i = 1; i <= rings; ++i) {
    const double s = static_cast<double>(i) / (rings + 1);
    outline.emplace_back(VaseRadius(s), kVaseHeight * (s - 0.5));
  }
  SceneObject vase;
  vase.id = kVaseId;
  vase.name = "vase";
  vase.motion = Motion::kRigid;
  vase.mesh_path = "breaking_vase.obj";
  vase.mesh = internal::LatheMesh(outline, -kVaseHeight / 2, kVaseHeight / 2, 2 * rings);
  return vase;
}

// The vase's path: lying on its side, rolling from the rim of the bowl into the rock, where it
// breaks at frame breaks_at.
struct Roll {
  Eigen::Vector2d start, direction, end;
  Eigen::Vector3d roll_axis;
  Eigen::Quaterniond lying;
  double depth;  // how far its lowest point sinks into the terrain
  int breaks_at;
};

Roll PlanRoll(int frames, Random* random) {
  Roll roll;
  roll.start =
      Eigen::Vector2d(-6.0 + random->Uniform(-0.5, 0.5), -1.5 + random->Uniform(-1.0, 1.0));
  roll.direction = (kRock - roll.start).normalized();
  roll.end = kRock - 0.75 * roll.direction;
  roll.roll_axis = Eigen::Vector3d(-roll.direction.y(), roll.direction.x(), 0);  // up x direction
  roll.lying = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), roll.roll_axis);
  roll.depth = random->Uniform(0.02, 0.04);
  roll.breaks_at = std::max(1, frames / 2);
  return roll;
}

// The vase (vertices p_OV) at frame f <= breaks_at, resting on the terrain.
Pose VasePose(const Roll& roll, const HeightField& terrain, std::span<const Eigen::Vector3d> p_OV,
              int f) {
  const double s = static_cast<double>(f) / roll.breaks_at;
  const double travelled = (roll.end - roll.start).norm() * s * s;  // speeding up down the slope
  const double angle = travelled / kRollRadius;
  const Eigen::Quaterniond rotation =
      Eigen::Quaterniond(Eigen::AngleAxisd(
          0.08 * std::sin(3 * angle), Eigen::Vector3d(roll.direction.x(), roll.direction.y(), 0))) *
      Eigen::Quaterniond(Eigen::AngleAxisd(angle, roll.roll_axis)) * roll.lying;
  return RestOn(terrain, p_OV, rotation, roll.start + travelled * roll.direction, roll.depth);
}

// Where a fragment goes after the break.
struct Flight {
  Pose X_WF;  // at the break
  Eigen::Vector2d direction;
  double distance, spin, depth;
  Eigen::Vector3d spin_axis;
};

// The fragments' flights, drawn fragment by fragment after the fracture's own draws.
std::vector<Flight> Flights(const std::vector<Fragment>& fragments, const Pose& X_WO_break,
                            const Eigen::Vector2d& direction, Random* random) {
  std::vector<Flight> flights;
  for (const Fragment& fragment : fragments) {
    Flight flight;
    const Eigen::Vector3d p_WF = X_WO_break.translation + X_WO_break.rotation * fragment.p_OF;
    flight.X_WF = internal::MakePose(p_WF, X_WO_break.rotation);
    // Outwards from the vase's center, carried on along its way.
    Eigen::Vector2d out = (p_WF - X_WO_break.translation).head<2>();
    if (out.norm() < 1e-6) out = Eigen::Vector2d(random->Uniform(-1, 1), random->Uniform(-1, 1));
    flight.direction = (0.6 * out.normalized() + 0.4 * direction).normalized();
    flight.distance = random->Uniform(1.5, 3.5);
    flight.spin = random->Uniform(2.0, 6.0);
    flight.spin_axis =
        Eigen::Vector3d(random->Uniform(-1, 1), random->Uniform(-1, 1), random->Uniform(-1, 1))
            .normalized();
    flight.depth = random->Uniform(0.02, 0.04);
    flights.push_back(flight);
  }
  return flights;
}

// The frame of the break: the vase goes, its fragments come where it was.
FrameUpdate BreakFrame(const std::vector<Fragment>& fragments, const std::vector<Flight>& flights) {
  FrameUpdate frame;
  frame.removals.push_back(kVaseId);
  for (size_t k = 0; k < fragments.size(); ++k) {
    SceneObject piece;
    piece.id = kVaseId + 1 + static_cast<uint32_t>(k);
    piece.name = "vase-fragment-" + std::to_string(k + 1);
    piece.motion = Motion::kRigid;
    piece.mesh_path = "breaking_fragment_" + std::to_string(piece.id) + ".obj";
    piece.mesh = fragments[k].mesh;
    piece.X_WO = flights[k].X_WF;
    frame.additions.push_back(std::move(piece));
  }
  return frame;
}

// A frame after the break, a fraction u of the way to the end: the fragments slide and tumble,
// slowing down, resting on the terrain.
FrameUpdate SlideFrame(const HeightField& terrain, const std::vector<Fragment>& fragments,
                       const std::vector<Flight>& flights, double u) {
  const double eased = 1 - (1 - u) * (1 - u);  // slowing down
  FrameUpdate frame;
  for (size_t k = 0; k < fragments.size(); ++k) {
    const Flight& flight = flights[k];
    const Eigen::Quaterniond rotation =
        internal::RotationVector(flight.spin * eased * flight.spin_axis) * flight.X_WF.rotation;
    const Eigen::Vector2d xy =
        flight.X_WF.translation.head<2>() + flight.distance * eased * flight.direction;
    frame.poses.emplace_back(kVaseId + 1 + static_cast<uint32_t>(k),
                             RestOn(terrain, fragments[k].mesh.p_MV, rotation, xy, flight.depth));
  }
  return frame;
}

}  // namespace

Scene BreakingScene(uint64_t seed, int frames, int min_static_triangles, int min_rigid_triangles,
                    int num_fragments) {
  Random random(seed);
  num_fragments = std::max(1, num_fragments);
  const HeightField terrain = Terrain(min_static_triangles);
  SceneObject vase = Vase(min_rigid_triangles);
  const std::vector<Eigen::Vector3d> vase_p_OV = vase.mesh.p_MV;  // vase.mesh moves into the scene

  // The draws, in the scene's order: the path, the fracture, then the flights.
  const Roll roll = PlanRoll(frames, &random);
  vase.X_WO = VasePose(roll, terrain, vase_p_OV, 0);
  const std::vector<Fragment> fragments =
      internal::Fracture(vase.mesh, num_fragments, Eigen::Vector3d::Zero(), random.engine());
  const std::vector<Flight> flights = Flights(
      fragments, VasePose(roll, terrain, vase_p_OV, roll.breaks_at), roll.direction, &random);

  Scene scene;
  scene.objects.push_back(TerrainObject(terrain));
  scene.objects.push_back(std::move(vase));
  // Rolling until the break, then the break, then sliding apart until the last frame.
  const int after = std::max(1, frames - 1 - roll.breaks_at);
  for (int f = 1; f < frames; ++f) {
    if (f < roll.breaks_at) {
      FrameUpdate frame;
      frame.poses.emplace_back(kVaseId, VasePose(roll, terrain, vase_p_OV, f));
      scene.frames.push_back(std::move(frame));
    } else if (f == roll.breaks_at) {
      scene.frames.push_back(BreakFrame(fragments, flights));
    } else {
      const double u = static_cast<double>(f - roll.breaks_at) / after;
      scene.frames.push_back(SlideFrame(terrain, fragments, flights, u));
    }
  }
  return scene;
}

}  // namespace far::scenes
