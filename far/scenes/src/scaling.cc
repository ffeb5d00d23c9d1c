// "scaling": tiles of one cloth and two spheres on a wavy ground, as many and as fine as a target
// triangle count asks for.

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

constexpr double kDt = 0.1;         // seconds per frame
constexpr double kTile = 4.0;       // metres
constexpr double kMargin = 0.5;     // ground beyond the outer tiles
constexpr double kRadius = 0.6;     // spheres
constexpr double kClothSide = 2.6;  // metres
constexpr double kGravity = 4.0;    // slow motion, so that falls last several frames
constexpr double kDepth = 0.03;     // how far a resting sphere sinks into the ground

double GroundHeight(double x, double y) {
  return 0.15 * std::sin(0.7 * x) * std::sin(0.6 * y + 0.4) + 0.05 * std::sin(1.9 * x + 0.7 * y);
}

struct Tile {
  Eigen::Vector2d center;
  double roll_phase, roll_speed;            // the rolling sphere, on a circle
  Eigen::Vector2d drop_xy, drop_direction;  // the falling sphere
  double drop_height, drop_distance;        // drop_height < 0: landed before frame 0
  Eigen::Vector2d cloth_center;             // the cloth
  double cloth_height, cloth_phase;
};

}  // namespace

Scene ScalingScene(uint64_t seed, int target_triangles, int frames) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };

  // Sizes: objects and resolution both grow as s.
  const double target = std::max(1000, target_triangles);
  const double s = std::sqrt(target / 5000.0);
  const int tiles = std::max(1, static_cast<int>(std::lround(2 * s)));
  const int cols = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(tiles))));
  const int rows = (tiles + cols - 1) / cols;
  // A UV sphere of `stacks` stacks and 2 * stacks slices has 4 stacks (stacks - 1) triangles.
  const double sphere_budget = 0.4 * target / (2 * tiles);
  const int stacks =
      std::max(3, static_cast<int>(std::lround((1 + std::sqrt(1 + sphere_budget)) / 2)));
  const int cloth_cells =
      std::max(2, static_cast<int>(std::lround(std::sqrt(0.3 * target / tiles / 2))));
  const Mesh sphere = SphereMesh(Eigen::Vector3d::Zero(), kRadius, stacks, 2 * stacks);
  // The ground takes the rest, in cells of about the same shape as its rectangle.
  const double rest = std::max(
      8.0, target - 2.0 * tiles * sphere.num_triangles() - 2.0 * tiles * cloth_cells * cloth_cells);
  const double width = cols * kTile + 2 * kMargin, depth = rows * kTile + 2 * kMargin;
  const int cells_y =
      std::max(2, static_cast<int>(std::lround(std::sqrt(rest / 2 * depth / width))));
  const int cells_x = std::max(2, static_cast<int>(std::lround(rest / (2.0 * cells_y))));
  const HeightField ground_field(Eigen::Vector2d(-kMargin, -kMargin),
                                 Eigen::Vector2d(cols * kTile + kMargin, rows * kTile + kMargin),
                                 cells_x, cells_y, GroundHeight);

  std::vector<Tile> layout(static_cast<size_t>(tiles));
  for (int i = 0; i < tiles; ++i) {
    Tile& tile = layout[static_cast<size_t>(i)];
    tile.center = kTile * Eigen::Vector2d(i % cols + 0.5, i / cols + 0.5);
    tile.roll_phase = uniform(0, 2 * std::numbers::pi);
    tile.roll_speed = (unit(rng) < 0.5 ? -1 : 1) * uniform(0.4, 0.6);
    const double angle = uniform(0, 2 * std::numbers::pi);
    tile.drop_xy = tile.center + 0.5 * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    const double heading = uniform(0, 2 * std::numbers::pi);
    tile.drop_direction = Eigen::Vector2d(std::cos(heading), std::sin(heading));
    tile.drop_height = uniform(-1.0, 2.5);
    tile.drop_distance = uniform(0.5, 1.0);
    tile.cloth_center = tile.center + Eigen::Vector2d(uniform(-0.2, 0.2), uniform(-0.2, 0.2));
    tile.cloth_height = uniform(-1.0, 1.5);
    tile.cloth_phase = uniform(0, 2 * std::numbers::pi);
  }

  // Ids: ground 1, then two spheres per tile, then one cloth per tile.
  const auto rolling_id = [](int tile) { return static_cast<uint32_t>(2 + 2 * tile); };
  const auto falling_id = [](int tile) { return static_cast<uint32_t>(3 + 2 * tile); };
  const auto cloth_id = [tiles](int tile) { return static_cast<uint32_t>(2 + 2 * tiles + tile); };

  const auto rolling_pose = [&](const Tile& tile, double t) {
    const double theta = tile.roll_phase + tile.roll_speed * t;
    const double rolled = 1.1 * tile.roll_speed * t / kRadius;  // arc length / radius
    const Eigen::Quaterniond rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ())) *
        Eigen::Quaterniond(Eigen::AngleAxisd(rolled, Eigen::Vector3d::UnitX()));
    const Eigen::Vector2d xy =
        tile.center + 1.1 * Eigen::Vector2d(std::cos(theta), std::sin(theta));
    return RestOn(ground_field, sphere.p_MV, rotation, xy, kDepth);
  };
  const auto falling_pose = [&](const Tile& tile, double t) {
    // Height above its resting place: a free fall from drop_height, then rolling on.
    const double land = tile.drop_height > 0 ? std::sqrt(2 * tile.drop_height / kGravity)
                                             : tile.drop_height;  // landed -drop_height s ago
    const double above = std::max(0.0, tile.drop_height - 0.5 * kGravity * t * t);
    const double rolled = t > land ? tile.drop_distance * (1 - std::exp(-(t - land) / 1.5)) : 0.0;
    const Eigen::Vector3d axis(-tile.drop_direction.y(), tile.drop_direction.x(), 0);
    Pose pose = RestOn(ground_field, sphere.p_MV,
                       Eigen::Quaterniond(Eigen::AngleAxisd(rolled / kRadius, axis)),
                       tile.drop_xy + rolled * tile.drop_direction, kDepth);
    pose.translation.z() += above;
    return pose;
  };
  const std::vector<TriangleIndices> cloth_triangles = [&] {
    Mesh grid;
    const auto index = [&](int i, int j) {
      return static_cast<uint32_t>(i * (cloth_cells + 1) + j);
    };
    for (int i = 0; i < cloth_cells; ++i) {
      for (int j = 0; j < cloth_cells; ++j) {
        grid.triangles.push_back({index(i, j), index(i + 1, j), index(i + 1, j + 1)});
        grid.triangles.push_back({index(i, j), index(i + 1, j + 1), index(i, j + 1)});
      }
    }
    return grid.triangles;
  }();
  // The cloth lies on the ground and over the rolling sphere (a tent around it), with waves
  // that cross both, after falling from its own height.
  const auto cloth_vertices = [&](const Tile& tile, const Pose& X_WS, double t) {
    const double lift = std::max(0.0, tile.cloth_height - 0.8 * t);
    const Eigen::Vector2d p_WS = X_WS.translation.head<2>();
    std::vector<Eigen::Vector3d> p_WV;
    p_WV.reserve(static_cast<size_t>((cloth_cells + 1) * (cloth_cells + 1)));
    for (int i = 0; i <= cloth_cells; ++i) {
      for (int j = 0; j <= cloth_cells; ++j) {
        const double u = kClothSide * (static_cast<double>(i) / cloth_cells - 0.5);
        const double v = kClothSide * (static_cast<double>(j) / cloth_cells - 0.5);
        const Eigen::Vector2d xy = tile.cloth_center + Eigen::Vector2d(u, v) +
                                   Eigen::Vector2d(0.05 * std::sin(1.3 * t + 1.3 * v), 0);
        const double wave = 0.04 * std::sin(2.2 * u + 1.7 * v - 1.5 * t + tile.cloth_phase);
        const double d = (xy - p_WS).norm();
        const double tent = X_WS.translation.z() +
                            (d < kRadius ? std::sqrt(kRadius * kRadius - d * d) : kRadius - d);
        const double z = std::max(ground_field.Height(xy.x(), xy.y()), tent) + wave + lift;
        p_WV.emplace_back(xy.x(), xy.y(), z);
      }
    }
    return p_WV;
  };

  Scene scene;
  SceneObject ground;
  ground.id = 1;
  ground.name = "ground";
  ground.motion = Motion::kStatic;
  ground.mesh_path = "scaling_ground.obj";
  ground.mesh = ground_field.ToMesh();
  scene.objects.push_back(std::move(ground));
  for (int i = 0; i < tiles; ++i) {
    const Tile& tile = layout[static_cast<size_t>(i)];
    for (const bool rolling : {true, false}) {
      SceneObject ball;
      ball.id = rolling ? rolling_id(i) : falling_id(i);
      ball.name = (rolling ? "rolling-sphere-" : "falling-sphere-") + std::to_string(i + 1);
      ball.motion = Motion::kRigid;
      ball.mesh_path = "scaling_sphere.obj";  // one mesh for all spheres
      ball.mesh = sphere;
      ball.X_WO = rolling ? rolling_pose(tile, 0.0) : falling_pose(tile, 0.0);
      scene.objects.push_back(std::move(ball));
    }
  }
  for (int i = 0; i < tiles; ++i) {
    const Tile& tile = layout[static_cast<size_t>(i)];
    SceneObject cloth;
    cloth.id = cloth_id(i);
    cloth.name = "cloth-" + std::to_string(i + 1);
    cloth.motion = Motion::kDeformable;
    cloth.mesh_path = "scaling_cloth_" + std::to_string(cloth.id) + ".obj";
    cloth.mesh.p_MV = cloth_vertices(tile, rolling_pose(tile, 0.0), 0.0);
    cloth.mesh.triangles = cloth_triangles;
    scene.objects.push_back(std::move(cloth));
  }
  for (int f = 1; f < frames; ++f) {
    const double t = kDt * f;
    FrameUpdate frame;
    for (int i = 0; i < tiles; ++i) {
      const Tile& tile = layout[static_cast<size_t>(i)];
      const Pose rolling = rolling_pose(tile, t);
      frame.poses.emplace_back(rolling_id(i), rolling);
      frame.poses.emplace_back(falling_id(i), falling_pose(tile, t));
      frame.vertices.push_back(
          internal::VertexUpdate(cloth_id(i), cloth_vertices(tile, rolling, t), cloth_triangles));
    }
    scene.frames.push_back(std::move(frame));
  }
  return scene;
}

}  // namespace far::scenes
