// "scaling": tiles of one cloth and two spheres on a wavy ground, as many and as fine as a target
// triangle count asks for.

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

using internal::HeightField;
using internal::kFrameSeconds;
using internal::Random;
using internal::RestOn;

constexpr double kTile = 4.0;       // metres
constexpr double kMargin = 0.5;     // ground beyond the outer tiles
constexpr double kRadius = 0.6;     // spheres
constexpr double kClothSide = 2.6;  // metres
constexpr double kGravity = 4.0;    // slow motion, so that falls last several frames
constexpr double kDepth = 0.03;     // how far a resting sphere sinks into the ground

double GroundHeight(double x, double y) {
  return 0.15 * std::sin(0.7 * x) * std::sin(0.6 * y + 0.4) + 0.05 * std::sin(1.9 * x + 0.7 * y);
}

// How many tiles, and how fine each object: objects and resolution both grow as s.
struct Sizes {
  double target;          // triangles asked for, at least 1000
  int tiles, cols, rows;  // tiles, in rows of `cols`
  int stacks;             // each sphere: `stacks` stacks and 2 * stacks slices
  int cloth_cells;        // each cloth: cloth_cells^2 quads
};

Sizes ChooseSizes(int target_triangles) {
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
  return Sizes{target, tiles, cols, rows, stacks, cloth_cells};
}

// The ground takes the rest, in cells of about the same shape as its rectangle.
HeightField GroundField(const Sizes& sizes, const Mesh& sphere) {
  const int tiles = sizes.tiles, cols = sizes.cols, rows = sizes.rows;
  const int cloth_cells = sizes.cloth_cells;
  const double rest = std::max(8.0, sizes.target - 2.0 * tiles * sphere.num_triangles() -
                                        2.0 * tiles * cloth_cells * cloth_cells);
  const double width = cols * kTile + 2 * kMargin, depth = rows * kTile + 2 * kMargin;
  const int cells_y =
      std::max(2, static_cast<int>(std::lround(std::sqrt(rest / 2 * depth / width))));
  const int cells_x = std::max(2, static_cast<int>(std::lround(rest / (2.0 * cells_y))));
  return {Eigen::Vector2d(-kMargin, -kMargin),
          Eigen::Vector2d(cols * kTile + kMargin, rows * kTile + kMargin), cells_x, cells_y,
          GroundHeight};
}

// What every tile's motion is made on: the ground, one sphere mesh for all spheres, one cloth
// grid for all cloths.
struct World {
  HeightField ground;
  Mesh sphere;
  int cloth_cells;
  std::vector<TriangleIndices> cloth_triangles;
};

World MakeWorld(const Sizes& sizes) {
  Mesh sphere = SphereMesh(Eigen::Vector3d::Zero(), kRadius, sizes.stacks, 2 * sizes.stacks);
  HeightField ground = GroundField(sizes, sphere);
  return World{std::move(ground), std::move(sphere), sizes.cloth_cells,
               internal::GridTriangles(sizes.cloth_cells)};
}

struct Tile {
  Eigen::Vector2d center;
  double roll_phase, roll_speed;            // the rolling sphere, on a circle
  Eigen::Vector2d drop_xy, drop_direction;  // the falling sphere
  double drop_height, drop_distance;        // drop_height < 0: landed before frame 0
  Eigen::Vector2d cloth_center;             // the cloth
  double cloth_height, cloth_phase;
};

// Every random number of the scene, tile by tile in this order (the scene depends on it).
std::vector<Tile> Layout(const Sizes& sizes, Random* random) {
  std::vector<Tile> layout(static_cast<size_t>(sizes.tiles));
  for (int i = 0; i < sizes.tiles; ++i) {
    Tile& tile = layout[static_cast<size_t>(i)];
    tile.center = kTile * Eigen::Vector2d(i % sizes.cols + 0.5, i / sizes.cols + 0.5);
    tile.roll_phase = random->Uniform(0, 2 * std::numbers::pi);
    tile.roll_speed = (random->Unit() < 0.5 ? -1 : 1) * random->Uniform(0.4, 0.6);
    const double angle = random->Uniform(0, 2 * std::numbers::pi);
    tile.drop_xy = tile.center + 0.5 * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    const double heading = random->Uniform(0, 2 * std::numbers::pi);
    tile.drop_direction = Eigen::Vector2d(std::cos(heading), std::sin(heading));
    tile.drop_height = random->Uniform(-1.0, 2.5);
    tile.drop_distance = random->Uniform(0.5, 1.0);
    tile.cloth_center =
        tile.center + Eigen::Vector2d(random->Uniform(-0.2, 0.2), random->Uniform(-0.2, 0.2));
    tile.cloth_height = random->Uniform(-1.0, 1.5);
    tile.cloth_phase = random->Uniform(0, 2 * std::numbers::pi);
  }
  return layout;
}

// Ids: ground 1, then two spheres per tile, then one cloth per tile.
uint32_t RollingId(int tile) { return static_cast<uint32_t>(2 + 2 * tile); }
uint32_t FallingId(int tile) { return static_cast<uint32_t>(3 + 2 * tile); }
uint32_t ClothId(int tiles, int tile) { return static_cast<uint32_t>(2 + 2 * tiles + tile); }

Pose RollingPose(const World& world, const Tile& tile, double t) {
  const double theta = tile.roll_phase + tile.roll_speed * t;
  const double rolled = 1.1 * tile.roll_speed * t / kRadius;  // arc length / radius
  const Eigen::Quaterniond rotation =
      Eigen::Quaterniond(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ())) *
      Eigen::Quaterniond(Eigen::AngleAxisd(rolled, Eigen::Vector3d::UnitX()));
  const Eigen::Vector2d xy = tile.center + 1.1 * Eigen::Vector2d(std::cos(theta), std::sin(theta));
  return RestOn(world.ground, world.sphere.p_MV, rotation, xy, kDepth);
}

Pose FallingPose(const World& world, const Tile& tile, double t) {
  // Height above its resting place: a free fall from drop_height, then rolling on.
  const double land = tile.drop_height > 0 ? std::sqrt(2 * tile.drop_height / kGravity)
                                           : tile.drop_height;  // landed -drop_height s ago
  const double above = std::max(0.0, tile.drop_height - 0.5 * kGravity * t * t);
  const double rolled = t > land ? tile.drop_distance * (1 - std::exp(-(t - land) / 1.5)) : 0.0;
  const Eigen::Vector3d axis(-tile.drop_direction.y(), tile.drop_direction.x(), 0);
  Pose pose = RestOn(world.ground, world.sphere.p_MV,
                     Eigen::Quaterniond(Eigen::AngleAxisd(rolled / kRadius, axis)),
                     tile.drop_xy + rolled * tile.drop_direction, kDepth);
  pose.translation.z() += above;
  return pose;
}

// The cloth lies on the ground and over the rolling sphere at X_WS (a tent around it), with
// waves that cross both, after falling from its own height.
std::vector<Eigen::Vector3d> ClothVertices(const World& world, const Tile& tile, const Pose& X_WS,
                                           double t) {
  const int cloth_cells = world.cloth_cells;
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
      const double tent =
          X_WS.translation.z() + (d < kRadius ? std::sqrt(kRadius * kRadius - d * d) : kRadius - d);
      const double z = std::max(world.ground.Height(xy.x(), xy.y()), tent) + wave + lift;
      p_WV.emplace_back(xy.x(), xy.y(), z);
    }
  }
  return p_WV;
}

SceneObject Ground(const World& world) {
  SceneObject ground;
  ground.id = 1;
  ground.name = "ground";
  ground.motion = Motion::kStatic;
  ground.mesh_path = "scaling_ground.obj";
  ground.mesh = world.ground.ToMesh();
  return ground;
}

SceneObject Sphere(const World& world, const Tile& tile, int i, bool rolling) {
  SceneObject ball;
  ball.id = rolling ? RollingId(i) : FallingId(i);
  ball.name = (rolling ? "rolling-sphere-" : "falling-sphere-") + std::to_string(i + 1);
  ball.motion = Motion::kRigid;
  ball.mesh_path = "scaling_sphere.obj";  // one mesh for all spheres
  ball.mesh = world.sphere;
  ball.X_WO = rolling ? RollingPose(world, tile, 0.0) : FallingPose(world, tile, 0.0);
  return ball;
}

SceneObject Cloth(const World& world, const Tile& tile, int tiles, int i) {
  SceneObject cloth;
  cloth.id = ClothId(tiles, i);
  cloth.name = "cloth-" + std::to_string(i + 1);
  cloth.motion = Motion::kDeformable;
  cloth.mesh_path = "scaling_cloth_" + std::to_string(cloth.id) + ".obj";
  cloth.mesh.p_MV = ClothVertices(world, tile, RollingPose(world, tile, 0.0), 0.0);
  cloth.mesh.triangles = world.cloth_triangles;
  return cloth;
}

// Frame 0: the ground, then the spheres tile by tile, then the cloths (the order of the ids).
std::vector<SceneObject> Objects(const World& world, const std::vector<Tile>& layout) {
  const int tiles = static_cast<int>(layout.size());
  std::vector<SceneObject> objects;
  objects.push_back(Ground(world));
  for (int i = 0; i < tiles; ++i) {
    for (const bool rolling : {true, false}) {
      objects.push_back(Sphere(world, layout[static_cast<size_t>(i)], i, rolling));
    }
  }
  for (int i = 0; i < tiles; ++i) {
    objects.push_back(Cloth(world, layout[static_cast<size_t>(i)], tiles, i));
  }
  return objects;
}

// The update at time t: both spheres' poses and the cloth's vertices, tile by tile.
FrameUpdate Frame(const World& world, const std::vector<Tile>& layout, double t) {
  const int tiles = static_cast<int>(layout.size());
  FrameUpdate frame;
  for (int i = 0; i < tiles; ++i) {
    const Tile& tile = layout[static_cast<size_t>(i)];
    const Pose rolling = RollingPose(world, tile, t);
    frame.poses.emplace_back(RollingId(i), rolling);
    frame.poses.emplace_back(FallingId(i), FallingPose(world, tile, t));
    frame.vertices.push_back(internal::VertexUpdate(
        ClothId(tiles, i), ClothVertices(world, tile, rolling, t), world.cloth_triangles));
  }
  return frame;
}

}  // namespace

Scene ScalingScene(uint64_t seed, int target_triangles, int frames) {
  Random random(seed);
  const Sizes sizes = ChooseSizes(target_triangles);
  const World world = MakeWorld(sizes);
  const std::vector<Tile> layout = Layout(sizes, &random);

  Scene scene;
  scene.objects = Objects(world, layout);
  for (int f = 1; f < frames; ++f) scene.frames.push_back(Frame(world, layout, kFrameSeconds * f));
  return scene;
}

}  // namespace far::scenes
