#include "study_scenes.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <sstream>
#include <utility>

#include <Eigen/Geometry>

#include "far/io/mesh_io.h"
#include "far/scenes/scenes.h"

namespace far_study {
namespace {

constexpr uint64_t kPaperSeed = 1;  // paper-leaves, breaking, paper-bunnies, scaling

far::Pose MakePose(const Eigen::Vector3d& translation, const Eigen::Quaterniond& rotation) {
  far::Pose pose;
  pose.translation = translation;
  pose.rotation = rotation.normalized();
  return pose;
}

int64_t CountTriangles(const std::vector<far::SceneObject>& objects) {
  int64_t total = 0;
  for (const auto& object : objects) total += object.mesh.num_triangles();
  return total;
}

double WorldDiagonal(const std::vector<far::SceneObject>& objects) {
  Eigen::AlignedBox3d box;
  for (const auto& object : objects) {
    const Eigen::Isometry3d X_WO = object.X_WO.ToIsometry();
    for (const auto& p : object.mesh.p_MV) box.extend(X_WO * p);
  }
  return box.isEmpty() ? 0.0 : box.diagonal().norm();
}

// Random soup: clusters drifting and tumbling rigidly, each along its own random path.
StudyScene MakeSoup(const SceneOptions& options) {
  StudyScene study;
  study.name = "soup";
  const double triangle_size = 1.0;
  const double cluster = triangle_size * std::cbrt(static_cast<double>(options.soup_triangles));
  // About two neighbours per cluster: world side from the cluster volume.
  const double world = cluster * std::cbrt(static_cast<double>(options.soup_objects)) * 0.9;
  study.scene.objects = far::scenes::RandomSoup(7, options.soup_objects, options.soup_triangles,
                                                world, triangle_size);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  struct Path {
    uint32_t id;
    far::Pose start;
    Eigen::Vector3d axis, drift;
    double spin, phase;
  };
  std::vector<Path> paths;
  for (const auto& object : study.scene.objects) {
    const Eigen::Vector3d axis = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized();
    const Eigen::Vector3d drift = 0.5 * cluster * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    const double spin = 0.1 * unit(rng);
    const double phase = std::numbers::pi * unit(rng);
    paths.push_back({object.id, object.X_WO, axis, drift, spin, phase});
  }
  for (int step = 1; step <= options.steps; ++step) {
    far::FrameUpdate frame;
    for (const Path& path : paths) {
      const Eigen::Vector3d p =
          path.start.translation + std::sin(0.3 * step + path.phase) * path.drift;
      const Eigen::Quaterniond q =
          path.start.rotation * Eigen::Quaterniond(Eigen::AngleAxisd(path.spin * step, path.axis));
      frame.poses.emplace_back(path.id, MakePose(p, q));
    }
    study.scene.frames.push_back(std::move(frame));
  }
  std::ostringstream text;
  text << options.soup_objects << " rigid clusters x " << options.soup_triangles
       << " random triangles (" << CountTriangles(study.scene.objects)
       << " triangles), poses change every step";
  study.description = text.str();
  return study;
}

// Splits every triangle into four at its edge midpoints (shared midpoints: a closed mesh stays
// closed, the surface does not move).
far::Mesh Subdivide(const far::Mesh& mesh) {
  far::Mesh out;
  out.p_MV = mesh.p_MV;
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoint;
  auto middle = [&](uint32_t a, uint32_t b) {
    const auto key = std::minmax(a, b);
    auto it = midpoint.find(key);
    if (it != midpoint.end()) return it->second;
    const auto index = static_cast<uint32_t>(out.p_MV.size());
    out.p_MV.push_back(0.5 * (mesh.p_MV[a] + mesh.p_MV[b]));
    midpoint.emplace(key, index);
    return index;
  };
  for (const auto& t : mesh.triangles) {
    const uint32_t ab = middle(t[0], t[1]), bc = middle(t[1], t[2]), ca = middle(t[2], t[0]);
    out.triangles.push_back({t[0], ab, ca});
    out.triangles.push_back({ab, t[1], bc});
    out.triangles.push_back({ca, bc, t[2]});
    out.triangles.push_back({ab, bc, ca});
  }
  return out;
}

// Two bunnies: A static, B moving rigidly through A (deep interpenetration at every step).
far::Result<StudyScene> MakeBunnies(const std::string& name, const SceneOptions& options,
                                    int subdivisions, int steps) {
  auto read = far::ReadMesh(options.bunny_path);
  if (!read.ok()) return read.error();
  far::Mesh mesh = std::move(*read);
  for (int i = 0; i < subdivisions; ++i) mesh = Subdivide(mesh);
  // Center the mesh at its box center; sizes below are in units of its largest side.
  Eigen::AlignedBox3d box;
  for (const auto& p : mesh.p_MV) box.extend(p);
  for (auto& p : mesh.p_MV) p -= box.center();
  const double size = box.sizes().maxCoeff();
  auto pose_b = [size](int step) {
    const double t = 0.35 * step;
    const Eigen::Vector3d p =
        size * Eigen::Vector3d(0.25 + 0.08 * std::cos(t), 0.05 * std::sin(t), 0.08);
    const Eigen::Quaterniond q(
        Eigen::AngleAxisd(0.5 + 0.2 * std::sin(t), Eigen::Vector3d(0.3, 1.0, 0.2).normalized()));
    return MakePose(p, q);
  };
  StudyScene study;
  study.name = name;
  study.scene.objects = {{1, "", mesh, far::Motion::kStatic, {}},
                         {2, "", mesh, far::Motion::kRigid, pose_b(0)}};
  for (int step = 1; step <= steps; ++step) {
    far::FrameUpdate frame;
    frame.poses.emplace_back(2, pose_b(step));
    study.scene.frames.push_back(std::move(frame));
  }
  std::ostringstream text;
  text << "two bunnies of " << mesh.num_triangles() << " triangles ("
       << std::filesystem::path(options.bunny_path).filename().string() << ", " << subdivisions
       << "x midpoint-subdivided), one static, one moving rigidly through it";
  study.description = text.str();
  return study;
}

// Leaves: the static tree and deformable leaves, re-generated at time 0.1 * step.
StudyScene MakeLeaves(const SceneOptions& options) {
  constexpr uint64_t kSeed = 5;
  constexpr double kDt = 0.1;
  StudyScene study;
  study.name = "leaves";
  study.kind = Kind::kDeformable;
  study.scene.objects = far::scenes::LeavesScene(kSeed, options.leaves, options.leaf_cells, 0.0);
  for (int step = 1; step <= options.steps; ++step) {
    far::FrameUpdate frame;
    for (auto& object :
         far::scenes::LeavesScene(kSeed, options.leaves, options.leaf_cells, kDt * step)) {
      if (object.motion == far::Motion::kDeformable)
        frame.vertices.emplace_back(object.id, std::move(object.mesh));
    }
    study.scene.frames.push_back(std::move(frame));
  }
  std::ostringstream text;
  text << "a static tree (" << study.scene.objects[0].mesh.num_triangles() << " triangles) and "
       << options.leaves << " deformable leaves of " << 2 * options.leaf_cells * options.leaf_cells
       << " triangles (" << CountTriangles(study.scene.objects)
       << " triangles), vertices change every step";
  study.description = text.str();
  return study;
}

// The paper's workloads from far/scenes; `steps` measured steps are frames 1..steps.
far::Result<StudyScene> MakePaperScene(const std::string& name, const SceneOptions& options) {
  StudyScene study;
  study.name = name;
  study.family = Family::kPaper;
  std::ostringstream text;
  if (name == "paper-leaves") {
    study.kind = Kind::kDeformable;
    study.scene = far::scenes::PaperLeavesScene(kPaperSeed, options.steps + 1);
    text << "PaperLeavesScene: a static tree (" << study.scene.objects[0].mesh.num_triangles()
         << " triangles) and " << study.scene.objects.size() - 1
         << " deformable leaves, vertices every step";
  } else if (name == "breaking") {
    // The break sits at the middle of the measured steps, with steps before and after it.
    const int steps = std::max(2, options.steps);
    const int frames = steps + 1;
    const int break_step = std::max(1, frames / 2);  // frame k is applied before step k
    study.kind = Kind::kBreaking;
    study.scene = far::scenes::BreakingScene(kPaperSeed, frames, options.breaking_static_triangles,
                                             options.breaking_rigid_triangles);
    study.break_step = break_step;
    study.key_steps = {break_step, break_step + 1};
    study.break_note = "the vase breaks at measured step " + std::to_string(break_step) + " of " +
                       std::to_string(steps);
    text << "BreakingScene: a static terrain (" << study.scene.objects[0].mesh.num_triangles()
         << " triangles) and a rigid vase (" << study.scene.objects[1].mesh.num_triangles()
         << ") rolling into a rock; " << study.break_note
         << " (removed, 12 rigid fragments added), poses every step";
  } else {
    auto bunny = far::ReadMesh(options.bunny_path);
    if (!bunny.ok()) return bunny.error();
    study.scene = far::scenes::BunniesScene(*bunny, options.paper_bunny_refinement, kPaperSeed,
                                            options.steps + 1);
    text << "BunniesScene: two bunnies of " << study.scene.objects[0].mesh.num_triangles()
         << " triangles (RefineMesh n = " << options.paper_bunny_refinement
         << "), one static, one moving rigidly through it";
  }
  study.description = text.str();
  return study;
}

StudyScene MakeScaling(int target, const SceneOptions& options) {
  StudyScene study;
  study.name = "scaling-" + std::to_string(target);
  study.family = Family::kScaling;
  study.nominal_triangles = target;
  study.kind = Kind::kDeformable;  // its cloths get vertices every step
  study.scene = far::scenes::ScalingScene(kPaperSeed, target, options.steps + 1);
  std::ostringstream text;
  text << "ScalingScene(" << target << "): " << study.scene.objects.size()
       << " objects (static ground, rolling and falling spheres, deformable cloths)";
  study.description = text.str();
  return study;
}

std::optional<int> ScalingTarget(const std::string& name) {
  const std::string prefix = "scaling-";
  if (name.rfind(prefix, 0) != 0 || name.size() == prefix.size()) return std::nullopt;
  const std::string digits = name.substr(prefix.size());
  if (!std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }) ||
      digits.size() > 8) {
    return std::nullopt;
  }
  return std::stoi(digits);
}

}  // namespace

std::string_view ToString(Family family) {
  switch (family) {
    case Family::kSmall:
      return "small";
    case Family::kPaper:
      return "paper";
    case Family::kScaling:
      return "scaling";
  }
  return "?";
}

std::string_view ToString(Kind kind) {
  switch (kind) {
    case Kind::kRigid:
      return "rigid";
    case Kind::kDeformable:
      return "deformable";
    case Kind::kBreaking:
      return "breaking";
  }
  return "?";
}

const std::vector<std::string>& FixedSceneNames() {
  static const std::vector<std::string> names = {
      "soup", "bunnies", "leaves", "bunnies-fine", "paper-leaves", "breaking", "paper-bunnies"};
  return names;
}

bool IsKnownScene(const std::string& name) {
  const auto& names = FixedSceneNames();
  return std::find(names.begin(), names.end(), name) != names.end() ||
         ScalingTarget(name).has_value();
}

far::Result<StudyScene> MakeStudyScene(const std::string& name, const SceneOptions& options) {
  far::Result<StudyScene> made =
      far::MakeError(far::ErrorCode::kInvalidArgument, "unknown scene '" + name + "'");
  if (name == "soup") {
    made = MakeSoup(options);
  } else if (name == "bunnies") {
    made = MakeBunnies(name, options, options.bunny_subdivisions, options.steps);
  } else if (name == "bunnies-fine") {
    // The ID-buffer-against-queries comparison at 20k+ triangles: FAR only, one resolution, a
    // few steps (occlusion queries are slow on a software rasterizer).
    made = MakeBunnies(name, options, options.bunny_subdivisions + options.fine_extra_subdivisions,
                       std::min(options.fine_steps, options.steps));
    if (made.ok()) made->far_only = true;
  } else if (name == "leaves") {
    made = MakeLeaves(options);
  } else if (name == "paper-leaves" || name == "breaking" || name == "paper-bunnies") {
    made = MakePaperScene(name, options);
  } else if (auto target = ScalingTarget(name)) {
    made = MakeScaling(*target, options);
  }
  if (!made.ok()) return made;
  made->triangles = CountTriangles(made->scene.objects);
  if (made->nominal_triangles == 0) made->nominal_triangles = made->triangles;
  made->diagonal = WorldDiagonal(made->scene.objects);
  return made;
}

}  // namespace far_study
