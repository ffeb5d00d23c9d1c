// What this measures, and why: the gpu method's kernels apart from the rest of its step
// (docs/culling.md, "The gpu method"): far::ComputeCollider::Run on far-study's scenes as they
// stand at measured step 1, where every object that moves in the scene goes up again each
// iteration (a new world key: its vertices are uploaded, its triangles' boxes and hierarchy
// refit), then the object pairs, the traversal, the filters and the read-back, as a step does.
// The study's step times add the CPU's update, exact tests and answer around this; comparing two
// builds of the kernels needs only this. Scenes: 0 paper-leaves, 1 scaling-50000,
// 2 scaling-150000, 3 scaling-1000000; the second argument 1 asks for distance pairs (D a
// thousandth of the scene's diagonal, as far-study's distance pass); the third 1 hands posed
// objects over with their pose, as the pipeline does (placed on the GPU where the device places
// exactly), 0 with their world vertices only (uploaded as they move). Counters, per step: the
// GPU's own times (refit_ms with the uploads; traverse_ms with the object pairs; filter_ms; 0
// where the driver's timer gives none: llvmpipe's reads about 0 for compute), the CPU's submit_ms
// and wait_ms (waiting and reading back; read_ms of it the reading), and the pairs: box_pairs
// (whose boxes met), crossing, undecided (to the CPU's exact predicates), uploaded_MB and placed
// (world vertices placed on the GPU).
//   far_compute_benchmark --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
//       --benchmark_report_aggregates_only=true [--gl-platform=device]

#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "gl_platform_flag.h"
#include "study_scenes.h"
#include <benchmark/benchmark.h>

#include "far/gpu/compute_collider.h"
#include "far/gpu/gl_context.h"
#include "far/pairs/exact_stage.h"
#include "far/pairs/sweep_and_prune.h"
#include "far/pairs/triangle_bvh.h"
#include "far/pairs/world_object.h"

namespace {

far::GlPlatform g_platform = far::GlPlatform::kAuto;  // --gl-platform
const char* const kScenes[] = {"paper-leaves", "scaling-50000", "scaling-150000",
                               "scaling-1000000"};

// One object as the gpu method's stage hands it over: world vertices, its hierarchy's topology
// (TriangleBvh's, built here from those vertices), its world box, and a posed object's own
// vertices and pose.
struct StepObject {
  std::vector<Eigen::Vector3d> p_WV;
  std::vector<Eigen::Vector3d> p_MV;  // empty: at the identity pose
  Eigen::Matrix<double, 3, 4> X_WM = Eigen::Matrix<double, 3, 4>::Zero();
  std::vector<far::TriangleIndices> triangles;
  std::vector<far::ComputeNode> nodes;
  std::vector<uint32_t> order;
  Eigen::AlignedBox3d box;
  bool moves = false;
};

// A scene at measured step 1, with the collider that runs it (its own buffers).
struct ComputeScene {
  std::unique_ptr<far::ComputeCollider> collider;
  std::vector<StepObject> objects;
  double diagonal = 0, magnitude = 0;
};

far::Result<ComputeScene> MakeComputeScene(const std::string& name) {
  far_study::SceneOptions options;
  options.steps = 1;
  auto study = far_study::MakeStudyScene(name, options);
  if (!study.ok()) return study.error();
  auto objects = far::ObjectsAtStep(study->scene, 1);
  if (!objects.ok()) return objects.error();
  ComputeScene scene;
  scene.diagonal = study->diagonal;
  for (const far::SceneObject& object : *objects) {
    StepObject& to = scene.objects.emplace_back();
    const Eigen::Isometry3d X_WO = object.X_WO.ToIsometry();
    for (const Eigen::Vector3d& p : object.mesh.p_MV) {
      to.p_WV.push_back(far::WorldVertex(X_WO, p));
      to.box.extend(to.p_WV.back());
    }
    to.triangles = object.mesh.triangles;
    to.moves = object.motion != far::Motion::kStatic;
    if (X_WO.matrix() != Eigen::Matrix4d::Identity()) {
      to.p_MV = object.mesh.p_MV;
      to.X_WM = X_WO.matrix().topRows<3>();
    }
    far::TriangleBvh bvh;
    if (!bvh.Build(to.p_WV, to.triangles)) {
      return far::MakeError(far::ErrorCode::kInternal, "could not build a hierarchy");
    }
    for (const far::TriangleBvh::Node& node : bvh.nodes())
      to.nodes.push_back({node.first, node.count});
    to.order = bvh.order();
    if (!to.box.isEmpty()) {
      scene.magnitude = std::max({scene.magnitude, to.box.min().cwiseAbs().maxCoeff(),
                                  to.box.max().cwiseAbs().maxCoeff()});
    }
  }
  auto collider = far::ComputeCollider::Create();
  if (!collider.ok()) return collider.error();
  scene.collider = std::move(*collider);
  return scene;
}

// Made once per scene, on the benchmark's thread, where the one context is current.
ComputeScene* SceneAt(int64_t index) {
  static const far::Result<std::unique_ptr<far::GlContext>> context =
      far::GlContext::Create(g_platform);
  if (!context.ok()) {
    std::fprintf(stderr, "far_compute_benchmark: %s\n", context.error().message.c_str());
    return nullptr;
  }
  static std::map<int64_t, far::Result<ComputeScene>> scenes;
  auto it = scenes.find(index);
  if (it == scenes.end()) it = scenes.emplace(index, MakeComputeScene(kScenes[index])).first;
  if (!it->second.ok()) {
    std::fprintf(stderr, "far_compute_benchmark: %s: %s\n", kScenes[index],
                 it->second.error().message.c_str());
    return nullptr;
  }
  return &*it->second;
}

void BM_Gpu(benchmark::State& state) {
  ComputeScene* scene = SceneAt(state.range(0));
  if (scene == nullptr) {
    state.SkipWithError("no scene (see stderr)");
    return;
  }
  const bool distance = state.range(1) != 0;
  // As the pipeline hands posed objects over (placed on the GPU from their pose where the device
  // places exactly), or with their world vertices only (uploaded whenever they move).
  const bool posed = state.range(2) != 0;
  const double max_distance = 0.001 * scene->diagonal;
  const double slack = distance ? far::CullSlack(max_distance, scene->magnitude) : 0.0;
  std::vector<far::ComputeObject> views;
  for (size_t s = 0; s < scene->objects.size(); ++s) {
    const StepObject& object = scene->objects[s];
    views.push_back({object.p_WV, object.triangles, object.nodes, object.order, s + 1, 1,
                     far::SweepAndPrune::GrownBox(object.box, slack)});
    if (posed && !object.p_MV.empty()) {
      views.back().p_MV = object.p_MV;
      views.back().X_WM = object.X_WM;
      views.back().model_key = s + 1;
    }
  }
  far::ComputeQuery query;
  query.objects = views;
  query.slack = slack;
  query.distance = distance;
  if (distance) query.max_distance = max_distance;
  // One step untimed first: the scene's layout going up and the buffers growing are one-off.
  if (auto warm = scene->collider->Run(query); !warm.ok()) {
    state.SkipWithError(warm.error().message.c_str());
    return;
  }
  uint64_t world_key = 1;
  std::map<std::string, double> sums;
  for (auto _ : state) {
    ++world_key;  // the moving objects go up and are refit again, as in a step
    for (size_t s = 0; s < views.size(); ++s) {
      if (scene->objects[s].moves) views[s].world_key = world_key;
    }
    auto answer = scene->collider->Run(query);
    if (!answer.ok()) {
      state.SkipWithError(answer.error().message.c_str());
      return;
    }
    sums["refit_ms"] += answer->gpu_refit_ms;
    sums["traverse_ms"] += answer->gpu_traverse_ms;
    sums["filter_ms"] += answer->gpu_filter_ms;
    sums["submit_ms"] += answer->cpu_submit_ms;
    sums["wait_ms"] += answer->cpu_wait_ms;
    sums["read_ms"] += answer->cpu_read_ms;
    sums["uploaded_MB"] += 1e-6 * static_cast<double>(answer->bytes_uploaded);
    sums["placed"] += static_cast<double>(answer->vertices_placed);
    sums["box_pairs"] += static_cast<double>(answer->box_pairs);
    sums["crossing"] += static_cast<double>(answer->crossing.size());
    sums["undecided"] += static_cast<double>(answer->undecided.size());
  }
  for (const auto& [name, sum] : sums) {
    state.counters[name] = benchmark::Counter(sum, benchmark::Counter::kAvgIterations);
  }
  state.SetLabel(std::string(kScenes[state.range(0)]) + (distance ? ", distance" : "") +
                 (posed ? "" : ", world vertices uploaded"));
}
// Arguments: the scene (kScenes), a distance query, posed objects handed over with their pose.
BENCHMARK(BM_Gpu)
    ->ArgsProduct({{0, 1, 2, 3}, {0}, {1, 0}})
    ->Args({0, 1, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  if (!far_study::TakeGlPlatformFlag(&argc, argv, &g_platform, "far_compute_benchmark")) return 2;
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
