// What this measures, and why: the kernel behind the bvh method against the alternatives on the
// same object pair, two closed, bumpy balls of n triangles each, one rotated and moved so that
// they interpenetrate deeply (a few thousand contacts at n = 20k):
// - BM_Pair_Bvh: far's hierarchy stage (RunBvhTests: simultaneous descent of the two
//   TriangleBvh in their own frames, exact tests at the leaves), hierarchies built beforehand
//   as for static and rigid objects;
// - BM_Pair_SortSweep: the exact stage's per-object sort-and-sweep on every triangle
//   (RunExactTests: what aabb does when the partner's box holds everything);
// - BM_Pair_Fcl: FCL's collide of two prebuilt BVHModel<OBBRSS> (every contact), as the fcl
//   method does per broadphase pair;
// - BM_Pair_BvhFans / BM_Pair_FclFans: the same on two fans of slivers (a fractured piece's
//   shape), bvh with its triangles' slabs (second argument 1) and without (0: refit in place);
// - BM_Hierarchy_Build / _Refit: the one-off cost of a rigid object and the per-step cost of a
//   deformable one.
// All of them find the same contacts (checked once, outside the timing; FCL's only up to its
// known narrowphase errors). Threads: the pool's count (second argument); FCL is single-threaded.
// Run, interleaved, with aggregates:
//   build/<dir>/bench/pairs/far_bvh_benchmark --benchmark_repetitions=5
//       --benchmark_enable_random_interleaving=true --benchmark_report_aggregates_only=true

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <vector>

#include <benchmark/benchmark.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/narrowphase/collision.h>

#include "far/pairs/bvh_stage.h"
#include "far/pairs/exact_stage.h"
#include "far/pairs/triangle_bvh.h"

namespace far {
namespace {

// A closed ball of about n triangles with bumps (2 k (k - 1) triangles for k bands).
Mesh Ball(int n, double radius) {
  const int k = std::max(3, static_cast<int>(std::sqrt(n / 2.0)) + 1);
  const double pi = std::acos(-1.0);
  Mesh mesh;
  mesh.p_MV.emplace_back(0, 0, radius);
  for (int i = 1; i < k; ++i) {
    for (int j = 0; j < 2 * k; ++j) {
      const double theta = pi * i / k, phi = pi * j / k;
      const double r = radius * (1 + 0.05 * std::sin(7 * phi) * std::sin(5 * theta));
      mesh.p_MV.emplace_back(r * std::sin(theta) * std::cos(phi),
                             r * std::sin(theta) * std::sin(phi), r * std::cos(theta));
    }
  }
  mesh.p_MV.emplace_back(0, 0, -radius);
  const auto ring = [k](int i, int j) {
    return static_cast<uint32_t>(1 + (i - 1) * 2 * k + (j % (2 * k)));
  };
  const auto bottom = static_cast<uint32_t>(mesh.p_MV.size() - 1);
  for (int j = 0; j < 2 * k; ++j) {
    mesh.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
    for (int i = 1; i + 1 < k; ++i) {
      mesh.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      mesh.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
    mesh.triangles.push_back({ring(k - 1, j), bottom, ring(k - 1, j + 1)});
  }
  return mesh;
}

// A fractured fragment's shape: a wavy loop of n / 2 points closed by two fans of slivers, one
// to an apex on each side (what far::scenes' Fracture closes a piece with): n long, thin,
// slanted triangles, whose axis-aligned boxes are loose.
Mesh Fans(int n) {
  const int loop = std::max(3, n / 2);
  const double pi = std::acos(-1.0);
  Mesh mesh;
  for (int i = 0; i < loop; ++i) {
    const double angle = 2 * pi * i / loop;
    mesh.p_MV.emplace_back(std::cos(angle), std::sin(angle), 0.15 * std::sin(9 * angle));
  }
  mesh.p_MV.emplace_back(0.2, -0.1, 0.5);
  mesh.p_MV.emplace_back(-0.1, 0.2, -0.4);
  const auto top = static_cast<uint32_t>(loop), bottom = top + 1;
  for (uint32_t i = 0; i < top; ++i) {
    mesh.triangles.push_back({i, (i + 1) % top, top});
    mesh.triangles.push_back({(i + 1) % top, i, bottom});
  }
  return mesh;
}

// Two copies of a mesh (balls: a deep, curved overlap; fans: slivers crossing each other), B
// moved half a radius off A's center and rotated.
struct PairScene {
  Mesh mesh;
  Eigen::Isometry3d X_WA = Eigen::Isometry3d::Identity(), X_WB = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Vector3d> p_WA, p_WB;
  TriangleBvh bvh;  // of the mesh in its own frame: both objects share it

  explicit PairScene(Mesh shape) : mesh(std::move(shape)) {
    X_WB.linear() =
        Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    X_WB.translation() = Eigen::Vector3d(0.5, 0.2, 0.1);
    for (const auto& p : mesh.p_MV) {
      p_WA.push_back(X_WA * p);
      p_WB.push_back(X_WB * p);
    }
    bvh.Build(mesh.p_MV, mesh.triangles);
  }
  std::vector<WorldObjectView> Views() const {
    return {{p_WA, mesh.triangles}, {p_WB, mesh.triangles}};
  }
};

const PairScene& Scene(int n, bool fans = false) {
  static std::map<std::pair<int, bool>, std::unique_ptr<PairScene>> scenes;
  auto& scene = scenes[{n, fans}];
  if (!scene) scene = std::make_unique<PairScene>(fans ? Fans(n) : Ball(n, 1.0));
  return *scene;
}

const std::vector<SlotPair> kPairs = {{SlotAt(0), SlotAt(1)}};

ExactResult RunBvh(const PairScene& scene, ThreadPool& pool, const TriangleBvh* bvh = nullptr) {
  if (bvh == nullptr) bvh = &scene.bvh;
  const std::vector<WorldObjectView> views = scene.Views();
  const std::vector<ObjectHierarchy> hierarchies = {{bvh, scene.X_WA}, {bvh, scene.X_WB}};
  BvhQuery query;
  query.objects = views;
  query.hierarchies = hierarchies;
  query.object_pairs = kPairs;
  query.want_candidates = false;
  return RunBvhTests(query, pool).exact;
}

ExactResult RunSortSweep(const PairScene& scene, ThreadPool& pool) {
  const std::vector<WorldObjectView> views = scene.Views();
  ExactQuery query;
  query.objects = views;
  query.object_pairs = kPairs;
  return RunExactTests(query, pool);
}

using Model = fcl::BVHModel<fcl::OBBRSSd>;

std::shared_ptr<Model> FclModel(const Mesh& mesh) {
  auto model = std::make_shared<Model>();
  std::vector<fcl::Vector3d> points(mesh.p_MV.begin(), mesh.p_MV.end());
  std::vector<fcl::Triangle> triangles;
  for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  model->beginModel();
  model->addSubModel(points, triangles);
  model->endModel();
  return model;
}

size_t RunFcl(const PairScene& scene, const std::shared_ptr<Model>& model) {
  fcl::CollisionObjectd a(model, scene.X_WA.linear(), scene.X_WA.translation());
  fcl::CollisionObjectd b(model, scene.X_WB.linear(), scene.X_WB.translation());
  fcl::CollisionRequestd request(std::numeric_limits<size_t>::max(), false);
  fcl::CollisionResultd result;
  fcl::collide(&a, &b, request, result);
  return result.numContacts();
}

void BM_Pair_Bvh(benchmark::State& state) {
  const PairScene& scene = Scene(static_cast<int>(state.range(0)));
  ThreadPool pool(static_cast<int>(state.range(1)));
  size_t contacts = 0;
  for (auto _ : state) contacts = RunBvh(scene, pool).contacts.size();
  state.counters["contacts"] = static_cast<double>(contacts);
}

// Fans of slivers, with the hierarchy as built (with the triangles' slabs) or refit in place
// (none: what a deformable object has); second argument 1 / 0.
void BM_Pair_BvhFans(benchmark::State& state) {
  const PairScene& scene = Scene(static_cast<int>(state.range(0)), /*fans=*/true);
  TriangleBvh without_slabs = scene.bvh;
  if (without_slabs.Refit(scene.mesh.p_MV, scene.mesh.triangles) ||
      !without_slabs.slabs().empty()) {
    state.SkipWithError("the refit rebuilt the hierarchy: it has slabs");
    return;
  }
  const TriangleBvh* bvh = state.range(1) ? &scene.bvh : &without_slabs;
  ThreadPool pool(2);
  ExactResult result;
  for (auto _ : state) result = RunBvh(scene, pool, bvh);
  state.counters["contacts"] = static_cast<double>(result.contacts.size());
  state.counters["tested"] = static_cast<double>(result.pairs_tested);
}

void BM_Pair_FclFans(benchmark::State& state) {
  const PairScene& scene = Scene(static_cast<int>(state.range(0)), /*fans=*/true);
  const auto model = FclModel(scene.mesh);
  size_t contacts = 0;
  for (auto _ : state) contacts = RunFcl(scene, model);
  state.counters["contacts"] = static_cast<double>(contacts);
}

void BM_Pair_SortSweep(benchmark::State& state) {
  const PairScene& scene = Scene(static_cast<int>(state.range(0)));
  ThreadPool pool(static_cast<int>(state.range(1)));
  size_t contacts = 0;
  for (auto _ : state) contacts = RunSortSweep(scene, pool).contacts.size();
  state.counters["contacts"] = static_cast<double>(contacts);
}

void BM_Pair_Fcl(benchmark::State& state) {
  const PairScene& scene = Scene(static_cast<int>(state.range(0)));
  const auto model = FclModel(scene.mesh);
  size_t contacts = 0;
  for (auto _ : state) contacts = RunFcl(scene, model);
  state.counters["contacts"] = static_cast<double>(contacts);
}

void BM_Hierarchy_Build(benchmark::State& state) {
  const PairScene& scene = Scene(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    TriangleBvh bvh;
    bvh.Build(scene.mesh.p_MV, scene.mesh.triangles);
    benchmark::DoNotOptimize(bvh.nodes().data());
  }
}

void BM_Hierarchy_Refit(benchmark::State& state) {
  const PairScene& scene = Scene(static_cast<int>(state.range(0)));
  TriangleBvh bvh = scene.bvh;
  std::vector<Eigen::Vector3d> moved = scene.mesh.p_MV;
  int step = 0;
  for (auto _ : state) {
    // A small deformation each time, as a cloth's step.
    const double wave = 1e-3 * ((++step % 2) ? 1 : -1);
    for (auto& p : moved) p.z() += wave * p.x();
    benchmark::DoNotOptimize(bvh.Refit(moved, scene.mesh.triangles));
  }
}

// The same contacts from every kernel (FCL's within its known narrowphase errors), once.
void CheckAgreement() {
  const PairScene& scene = Scene(20000);
  ThreadPool pool(2);
  const size_t bvh = RunBvh(scene, pool).contacts.size();
  const size_t sweep = RunSortSweep(scene, pool).contacts.size();
  const size_t fcl = RunFcl(scene, FclModel(scene.mesh));
  std::fprintf(stderr, "contacts at n=20000: bvh %zu, sort-and-sweep %zu, fcl %zu%s\n", bvh, sweep,
               fcl, bvh == sweep ? "" : "  MISMATCH");
}

BENCHMARK(BM_Pair_Bvh)
    ->Args({20000, 1})
    ->Args({20000, 2})
    ->Args({80000, 2})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Pair_BvhFans)->Args({4000, 1})->Args({4000, 0})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Pair_FclFans)->Arg(4000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Pair_SortSweep)->Args({20000, 2})->Args({80000, 2})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Pair_Fcl)->Args({20000, 1})->Args({80000, 1})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Hierarchy_Build)->Arg(20000)->Arg(80000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Hierarchy_Refit)->Arg(20000)->Arg(80000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace far

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  far::CheckAgreement();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
