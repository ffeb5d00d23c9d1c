#include "gpu_probe.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>

#include "step_runner.h"

#include "far/gpu/culling_renderer.h"
#include "far/gpu/gl_lock.h"

namespace far::internal {
namespace {

// A closed, bumpy ball of 2 * n * (n - 1) triangles.
Mesh Ball(double radius, int n) {
  Mesh mesh;
  const double pi = std::acos(-1.0);
  mesh.p_MV.emplace_back(0, 0, radius);
  for (int i = 1; i < n; ++i) {
    for (int j = 0; j < 2 * n; ++j) {
      const double theta = pi * i / n, phi = pi * j / n;
      const double r = radius * (1 + 0.1 * std::sin(5 * phi) * std::sin(3 * theta));
      mesh.p_MV.emplace_back(r * std::sin(theta) * std::cos(phi),
                             r * std::sin(theta) * std::sin(phi), r * std::cos(theta));
    }
  }
  mesh.p_MV.emplace_back(0, 0, -radius);
  const auto ring = [n](int i, int j) {
    return static_cast<uint32_t>(1 + (i - 1) * 2 * n + (j % (2 * n)));
  };
  const auto bottom = static_cast<uint32_t>(mesh.p_MV.size() - 1);
  for (int j = 0; j < 2 * n; ++j) {
    mesh.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
    for (int i = 1; i + 1 < n; ++i) {
      mesh.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      mesh.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
    mesh.triangles.push_back({ring(n - 1, j), bottom, ring(n - 1, j + 1)});
  }
  return mesh;
}

// The time of a step of `method` (the second: the first builds shaders, pieces and
// hierarchies) over 27 overlapping balls of ball_n bands; `triangles` gets their count. The
// step runs on a world of its own, in the context current on this thread, with the pipeline's
// own stages (step_runner.h).
std::optional<double> Measure(Method method, int ball_n, int* triangles) {
  ThreadPool pool(1);
  StepWorld world(pool, /*with_gpu=*/true);
  // 27 balls on a grid, each overlapping its neighbours.
  const Mesh ball = Ball(0.6, ball_n);
  *triangles = 27 * ball.num_triangles();
  uint32_t id = 0;
  for (int x = 0; x < 3; ++x) {
    for (int y = 0; y < 3; ++y) {
      for (int z = 0; z < 3; ++z) {
        Pose pose;
        pose.translation = Eigen::Vector3d(x, y, z);
        world.Apply(AddObject{id++, ball, Motion::kRigid, pose});
      }
    }
  }
  StepRequest request;
  request.method = method;
  request.mechanism = QueryMechanism::kIdBuffer;
  request.resolution = 256;
  if (!RunStep(world, request, {})) return std::nullopt;  // shaders, buffers, pieces
  const auto start = std::chrono::steady_clock::now();
  if (!RunStep(world, request, {})) return std::nullopt;
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return ms;
}

// This process's costs, by renderer (measured or adopted).
std::mutex cost_mutex;
std::map<std::string, GpuCost> cost_by_renderer;

std::optional<GpuCost> KnownCost(const std::string& renderer) {
  std::lock_guard lock(cost_mutex);
  auto it = cost_by_renderer.find(renderer);
  if (it == cost_by_renderer.end()) return std::nullopt;
  return it->second;
}

}  // namespace

std::optional<GpuCost> ProbeGpuCost() {
  const auto gl = LockGl();
  const std::string renderer = CurrentGlRenderer();
  if (renderer.empty()) return std::nullopt;
  if (auto known = KnownCost(renderer)) return known;
  // Two sizes give the fixed part (clears, reads back, draw calls) and the part per triangle.
  int small_triangles = 0, large_triangles = 0;
  const std::optional<double> small = Measure(Method::kFar, 5, &small_triangles);
  const std::optional<double> large = Measure(Method::kFar, 9, &large_triangles);
  if (!small || !large) return std::nullopt;
  GpuCost cost;
  cost.ms_per_triangle = std::max(0.0, (*large - *small) / (large_triangles - small_triangles));
  cost.fixed_ms = std::max(0.0, *small - cost.ms_per_triangle * small_triangles);
  // The gpu method on the same scenes (its step is mostly fixed cost on a GPU).
  const std::optional<double> compute_small = Measure(Method::kGpu, 5, &small_triangles);
  const std::optional<double> compute_large = Measure(Method::kGpu, 9, &large_triangles);
  if (compute_small && compute_large) {
    const double per_triangle =
        std::max(0.0, (*compute_large - *compute_small) / (large_triangles - small_triangles));
    cost.compute_ms_per_triangle = per_triangle;
    cost.compute_fixed_ms = std::max(0.0, *compute_small - per_triangle * small_triangles);
  }
  std::lock_guard lock(cost_mutex);
  cost_by_renderer[renderer] = cost;
  return cost;
}

bool AdoptGpuCost(const GpuCost& cost) {
  const auto gl = LockGl();  // as ProbeGpuCost: the renderer is read from the context
  const std::string renderer = CurrentGlRenderer();
  if (renderer.empty()) return false;
  std::lock_guard lock(cost_mutex);
  cost_by_renderer[renderer] = cost;
  return true;
}

}  // namespace far::internal
