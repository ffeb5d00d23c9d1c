#include "far/pipeline/pipeline.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <optional>
#include <set>
#include <string>

#include "fcl_collider.h"
#include "gpu_culler.h"
#include "gpu_probe.h"
#include "guarantee.h"
#include "scene_cache.h"

#include "far/gpu/culling_renderer.h"
#include "far/gpu/gl_lock.h"
#include "far/model/limits.h"
#include "far/pairs/bvh_stage.h"
#include "far/pairs/exact_stage.h"
#include "far/pairs/sweep_and_prune.h"
#include "far/pairs/thread_pool.h"
#include "far/pipeline/internal/auto_selector.h"

namespace far {
namespace {

using internal::CachedObject;
using Clock = std::chrono::steady_clock;

bool IsGpuMethod(Method method) {
  return method == Method::kFar || method == Method::kFarExactOffset || method == Method::kCullide;
}

// The CPU culling methods: every object goes to sweep-and-prune, the object PCS is the objects
// in some pair.
bool IsCpuCulling(Method method) { return method == Method::kAabb || method == Method::kBvh; }

bool WantsExact(Output output) {
  return output == Output::kContacts || output == Output::kDistancePairs;
}

// Times the stages of one step into its stats.
class StageTimer {
 public:
  explicit StageTimer(StepStats& stats) : stats_(stats) {}
  void End(const char* stage) {
    const auto now = Clock::now();
    stats_.stages.push_back({stage, Milliseconds(stage_start_, now)});
    stage_start_ = now;
  }
  void Finish() { stats_.total_ms = Milliseconds(step_start_, Clock::now()); }

 private:
  static double Milliseconds(Clock::time_point from, Clock::time_point to) {
    return std::chrono::duration<double, std::milli>(to - from).count();
  }
  StepStats& stats_;
  Clock::time_point step_start_ = Clock::now();
  Clock::time_point stage_start_ = step_start_;
};

// What the stages of one step hand each other.
struct StepState {
  const StepRequest& request;
  const StepControl& control;
  std::vector<const CachedObject*> objects;    // id order; index i is the object's group
  std::vector<uint8_t> object_alive;           // per object: in the object PCS
  std::vector<std::vector<uint32_t>> subsets;  // per object: its triangles in the primitive PCS
  double cull_margin = 0;                      // CullMargin, once the world boxes are known
  StepResult result;
};

// Why a step stopped, as its error: the caller's cancellation, its deadline, the reply cap.
Error StopError(StopReason reason, std::string_view stage, const StepControl& control) {
  const std::string where = " (during " + std::string(stage) + ")";
  switch (reason) {
    case StopReason::kCancelled:
      return MakeError(ErrorCode::kUnavailable, "step cancelled by its caller" + where);
    case StopReason::kDeadline:
      return MakeError(ErrorCode::kTimeout, "step stopped at its deadline" + where);
    case StopReason::kPairLimit:
      return MakeError(ErrorCode::kLimitExceeded,
                       "the answer has more than " + std::to_string(control.max_pairs) +
                           " contact and distance pairs, the most a reply may carry" + where +
                           ": ask for a smaller distance D, or a shallower output (pcs)");
    case StopReason::kNone:
      break;
  }
  return MakeError(ErrorCode::kInternal, "step stopped for no reason" + where);
}

// The start of a stage: progress for the caller, and the check that the step may go on.
Result<void> EnterStage(const StepState& state, std::string_view stage) {
  if (state.control.on_stage) state.control.on_stage(stage);
  const StopReason reason = state.control.Check();
  if (reason != StopReason::kNone) return StopError(reason, stage, state.control);
  return {};
}

// The configuration a request runs: "bvh", "far/id-buffer/1024".
std::string ConfigName(const StepRequest& request) {
  return internal::Candidate{request.method, request.mechanism, request.resolution}.Name();
}

// Sorts and deduplicates every list.
void SortUnique(std::vector<uint32_t>& values) {
  std::sort(values.begin(), values.end());
  values.erase(std::unique(values.begin(), values.end()), values.end());
}

// The AABB baseline's primitive PCS: per object of a candidate pair, the triangles whose box
// overlaps the partner object's box grown by `margin` (CullMargin). A large scene takes seconds
// here: `control` is checked every kTrianglesPerCheck triangles.
Result<std::vector<std::vector<uint32_t>>> TrianglesInPartnerBoxes(
    std::span<const CachedObject* const> objects, std::span<const ObjectPair> pairs,
    const std::map<uint32_t, size_t>& index_of, double margin, const StepControl& control) {
  constexpr size_t kTrianglesPerCheck = 1 << 16;
  std::vector<std::vector<uint32_t>> subsets(objects.size());
  size_t unchecked = 0;
  for (const auto& pair : pairs) {
    const size_t a = index_of.at(pair.object_a), b = index_of.at(pair.object_b);
    for (auto [self, other] : {std::make_pair(a, b), std::make_pair(b, a)}) {
      Eigen::AlignedBox3d partner = objects[other]->box_W;
      partner.min().array() -= margin;
      partner.max().array() += margin;
      const CachedObject& object = *objects[self];
      for (size_t t = 0; t < object.mesh.triangles.size(); ++t) {
        if (++unchecked == kTrianglesPerCheck) {
          unchecked = 0;
          if (const StopReason reason = control.Check(); reason != StopReason::kNone)
            return StopError(reason, "primitive_cull", control);
        }
        Eigen::AlignedBox3d box;
        for (uint32_t v : object.mesh.triangles[t]) box.extend(object.p_WV[v]);
        if (box.intersects(partner)) subsets[self].push_back(static_cast<uint32_t>(t));
      }
    }
  }
  for (auto& subset : subsets) SortUnique(subset);
  return subsets;
}

// Object PCS, object pairs and primitive PCS implied by the pairs of an exact answer (what the
// whole-scene methods, exact and fcl, report for the culling outputs).
void DeriveCullingOutputs(StepResult& result) {
  std::set<uint32_t> pcs;
  std::set<ObjectPair> pairs;
  auto note = [&](const ContactPair& c) {
    pcs.insert({c.object_a, c.object_b});
    pairs.insert({c.object_a, c.object_b});
    result.pcs_primitives[c.object_a].push_back(c.triangle_a);
    result.pcs_primitives[c.object_b].push_back(c.triangle_b);
  };
  for (const auto& c : result.contacts) note(c);
  for (const auto& d : result.distance_pairs) note(d.pair);
  for (auto& [id, triangles] : result.pcs_primitives) SortUnique(triangles);
  result.pcs_objects.assign(pcs.begin(), pcs.end());
  result.object_pairs.assign(pairs.begin(), pairs.end());
  result.stats.object_pairs = static_cast<int64_t>(pairs.size());
}

}  // namespace

struct Pipeline::Impl {
  PipelineOptions options;
  std::unique_ptr<GlContext> gl;  // owned context, unless the caller's current one is used
  std::string renderer_name = "none";
  ThreadPool pool;
  SceneModel model;
  internal::SceneCache cache;
  std::unique_ptr<internal::GpuCuller> gpu;  // only with GL
  SweepAndPrune sap;
  internal::FclCollider fcl;
  std::optional<internal::AutoSelector> selector;  // made on the first auto step

  explicit Impl(const PipelineOptions& o)
      : options(o), pool(o.num_threads), model(o.scene_limits, o.shared_budget) {}

  Result<void> Apply(std::vector<SceneUpdate> updates,
                     const std::function<std::string(size_t)>& where);
  Result<StepResult> Step(const StepRequest& request, const StepControl& control);
  Result<StepResult> StepAuto(const StepRequest& request, const StepControl& control);
  Result<void> RunStages(StepState& state, StageTimer& timer);
  Result<void> RunWholeScene(StepState& state);
  Result<void> CullObjectsStage(StepState& state);
  void PairObjectsStage(StepState& state);
  Result<void> CullPrimitivesStage(StepState& state);
  Result<void> ExactStage(StepState& state);
  Result<void> HierarchyStage(StepState& state);
  BvhResult DescendHierarchies(StepState& state, bool run_exact,
                               std::vector<const CachedObject*>& paired);
};

Result<void> Pipeline::Impl::Apply(std::vector<SceneUpdate> updates,
                                   const std::function<std::string(size_t)>& where) {
  // The model checks the whole batch first; then nothing can fail.
  if (auto ok = model.Apply(updates, where); !ok) return ok;
  for (SceneUpdate& update : updates) {
    const uint32_t id = ObjectIdOf(update);
    const int64_t freed_slot = cache.Apply(std::move(update));
    if (freed_slot < 0) continue;
    // A removed object's GPU pieces and FCL model go with it (its id and slot may come back).
    if (gpu) gpu->RemoveSlot(static_cast<uint32_t>(freed_slot));
    fcl.Remove(id);
  }
  return {};
}

// The reference (every triangle pair) and FCL answer in one stage, without culling.
Result<void> Pipeline::Impl::RunWholeScene(StepState& state) {
  StepResult& result = state.result;
  ExactResult exact;
  std::optional<size_t> broadphase_pairs;  // FCL's candidate object pairs
  if (state.request.method == Method::kExact) {
    const std::vector<WorldObjectView> world = cache.WorldViews();
    if (const uint64_t pairs = BruteForcePairs(world); pairs > kMaxBruteForcePairs) {
      return MakeError(ErrorCode::kLimitExceeded,
                       "method 'exact' is the brute-force reference: this scene has " +
                           std::to_string(pairs) + " cross-object triangle pairs, over its limit " +
                           std::to_string(kMaxBruteForcePairs) +
                           "; 'bvh' gives the same exact answer");
    }
    exact = BruteForceReference(world, state.request.distance, pool, &state.control);
  } else {
    std::vector<internal::FclCollider::Object> fcl_objects;
    for (const CachedObject* object : state.objects) {
      fcl_objects.push_back({object->id, object->geometry_stamp, &object->mesh, object->X_WM});
    }
    internal::FclCollider::CollideStats fcl_stats;
    exact.contacts = fcl.Collide(fcl_objects, &fcl_stats, &state.control);
    exact.pairs_considered = fcl_stats.triangle_pairs_considered;
    exact.pairs_tested = fcl_stats.triangle_tests;
    exact.stopped = fcl_stats.stopped;
    broadphase_pairs = fcl_stats.object_pairs;
  }
  if (exact.stopped != StopReason::kNone) return StopError(exact.stopped, "exact", state.control);
  result.contacts = std::move(exact.contacts);
  result.distance_pairs = std::move(exact.distance_pairs);
  result.stats.pairs_tested = static_cast<int64_t>(exact.pairs_tested);
  result.stats.pairs_considered = static_cast<int64_t>(exact.pairs_considered);
  DeriveCullingOutputs(result);
  if (broadphase_pairs) result.stats.object_pairs = static_cast<int64_t>(*broadphase_pairs);
  return {};
}

// Object-level culling -> object PCS (AABB: every object goes on to sweep-and-prune).
Result<void> Pipeline::Impl::CullObjectsStage(StepState& state) {
  if (IsGpuMethod(state.request.method)) {
    cache.RefreshGpuGeometry(pool);
    cache.RefreshHierarchies(state.objects, pool, state.control);
    auto alive = gpu->CullObjects(state.request, state.objects, state.result.stats, state.control);
    if (!alive) return alive.error();
    state.object_alive = std::move(*alive);
  } else {
    state.object_alive.assign(state.objects.size(), 1);
  }
  if (IsCpuCulling(state.request.method)) return {};  // its PCS comes from the pairs
  for (size_t i = 0; i < state.objects.size(); ++i) {
    if (state.object_alive[i]) state.result.pcs_objects.push_back(state.objects[i]->id);
  }
  return {};
}

namespace {

// How much the CPU culls (sweep-and-prune, the aabb method's triangle boxes) grow boxes: 0 for
// contacts (closed boxes that touch overlap), CullSlack for a distance query, so that they drop
// no pair the exact tests would report.
double CullMargin(const StepState& state) {
  if (!state.request.distance) return 0.0;
  double magnitude = 0;
  for (const CachedObject* object : state.objects) {
    if (object->box_W.isEmpty()) continue;
    magnitude = std::max({magnitude, object->box_W.min().cwiseAbs().maxCoeff(),
                          object->box_W.max().cwiseAbs().maxCoeff()});
  }
  return CullSlack(*state.request.distance, magnitude);
}

}  // namespace

// Sweep-and-prune on the PCS objects' AABBs (margin CullMargin for distance queries).
void Pipeline::Impl::PairObjectsStage(StepState& state) {
  std::vector<IdBox> id_boxes;
  for (size_t i = 0; i < state.objects.size(); ++i) {
    if (state.object_alive[i]) id_boxes.push_back({state.objects[i]->id, state.objects[i]->box_W});
  }
  StepResult& result = state.result;
  result.object_pairs = sap.Update(id_boxes, state.cull_margin);
  result.stats.object_pairs = static_cast<int64_t>(result.object_pairs.size());
  if (IsCpuCulling(state.request.method)) {
    // I-COLLIDE: the PCS is the set of objects in some overlapping pair.
    std::set<uint32_t> paired;
    for (const auto& pair : result.object_pairs) paired.insert({pair.object_a, pair.object_b});
    result.pcs_objects.assign(paired.begin(), paired.end());
  }
}

// Sub-object culling of the objects in candidate pairs -> primitive PCS.
Result<void> Pipeline::Impl::CullPrimitivesStage(StepState& state) {
  StepResult& result = state.result;
  std::map<uint32_t, size_t> index_of;
  for (size_t i = 0; i < state.objects.size(); ++i) index_of[state.objects[i]->id] = i;
  std::set<size_t> paired_set;
  for (const auto& pair : result.object_pairs) {
    paired_set.insert({index_of[pair.object_a], index_of[pair.object_b]});
  }
  const std::vector<size_t> paired(paired_set.begin(), paired_set.end());
  if (IsGpuMethod(state.request.method)) {
    // The GPU draws only the triangles the hierarchies found near a partner: elsewhere there is
    // nothing for it to prune.
    std::vector<const CachedObject*> descended;
    BvhResult near = DescendHierarchies(state, /*run_exact=*/false, descended);
    if (near.exact.stopped != StopReason::kNone)
      return StopError(near.exact.stopped, "primitive_cull", state.control);
    std::vector<std::vector<uint32_t>> candidates(state.objects.size());
    for (size_t i = 0; i < descended.size(); ++i)
      candidates[index_of.at(descended[i]->id)] = std::move(near.candidates[i]);
    auto subsets = gpu->CullPrimitives(state.request, state.objects, paired, candidates,
                                       result.stats, state.control);
    if (!subsets) return subsets.error();
    state.subsets = std::move(*subsets);
  } else {
    auto subsets = TrianglesInPartnerBoxes(state.objects, result.object_pairs, index_of,
                                           state.cull_margin, state.control);
    if (!subsets) return subsets.error();
    state.subsets = std::move(*subsets);
  }
  for (size_t i : paired) {
    if (!state.subsets[i].empty()) result.pcs_primitives[state.objects[i]->id] = state.subsets[i];
  }
  return {};
}

// Exact tests on the CPU pool: PCS triangles of candidate object pairs.
Result<void> Pipeline::Impl::ExactStage(StepState& state) {
  const std::vector<WorldObjectView> world = cache.WorldViews();
  StepResult& result = state.result;
  ExactQuery query;
  query.objects = world;
  query.object_pairs = result.object_pairs;
  query.triangle_subsets = state.subsets;
  query.want_contacts = true;
  query.max_distance =
      state.request.output == Output::kDistancePairs ? state.request.distance : std::nullopt;
  query.control = &state.control;
  ExactResult exact = RunExactTests(query, pool);
  if (exact.stopped != StopReason::kNone) return StopError(exact.stopped, "exact", state.control);
  result.contacts = std::move(exact.contacts);
  result.distance_pairs = std::move(exact.distance_pairs);
  result.stats.pairs_considered = static_cast<int64_t>(exact.pairs_considered);
  result.stats.pairs_tested = static_cast<int64_t>(exact.pairs_tested);
  return {};
}

// The objects in some candidate pair, with their hierarchies brought up to date, and the
// simultaneous descent of each pair's hierarchies: candidate triangles (near a partner's
// triangle, within D), and the exact answer when `run_exact`.
BvhResult Pipeline::Impl::DescendHierarchies(StepState& state, bool run_exact,
                                             std::vector<const CachedObject*>& paired) {
  std::map<uint32_t, const CachedObject*> by_id;
  for (const CachedObject* object : state.objects) by_id[object->id] = object;
  for (const ObjectPair& pair : state.result.object_pairs) {
    paired.push_back(by_id.at(pair.object_a));
    paired.push_back(by_id.at(pair.object_b));
  }
  std::sort(paired.begin(), paired.end());
  paired.erase(std::unique(paired.begin(), paired.end()), paired.end());
  cache.RefreshHierarchies(paired, pool, state.control);
  std::vector<BvhObject> objects;
  for (const CachedObject* object : paired) {
    objects.push_back(
        {{object->id, object->p_WV, object->mesh.triangles}, &object->bvh, object->X_WM});
  }
  BvhQuery query;
  query.objects = objects;
  query.object_pairs = state.result.object_pairs;
  query.run_exact = run_exact;
  query.max_distance = state.request.distance;
  query.want_distance_pairs = state.request.output == Output::kDistancePairs;
  query.control = &state.control;
  return RunBvhTests(query, pool);
}

// The bvh method after sweep-and-prune: the descent, with the exact tests at the leaves when the
// output needs them; the triangles met on the way are the primitive PCS.
Result<void> Pipeline::Impl::HierarchyStage(StepState& state) {
  StepResult& result = state.result;
  const bool run_exact = WantsExact(state.request.output);
  std::vector<const CachedObject*> paired;
  BvhResult found = DescendHierarchies(state, run_exact, paired);
  if (found.exact.stopped != StopReason::kNone)
    return StopError(found.exact.stopped, run_exact ? "exact" : "primitive_cull", state.control);
  for (size_t i = 0; i < paired.size(); ++i) {
    if (!found.candidates[i].empty())
      result.pcs_primitives[paired[i]->id] = std::move(found.candidates[i]);
  }
  result.contacts = std::move(found.exact.contacts);
  result.distance_pairs = std::move(found.exact.distance_pairs);
  result.stats.descent = found.counters;
  result.stats.pairs_considered = static_cast<int64_t>(found.exact.pairs_considered);
  result.stats.pairs_tested = static_cast<int64_t>(found.exact.pairs_tested);
  return {};
}

// An auto step: the selector chooses a configuration, the step runs it and its time is
// recorded (auto_selector.h says how it chooses).
Result<StepResult> Pipeline::Impl::StepAuto(const StepRequest& request,
                                            const StepControl& control) {
  if (!selector) {
    selector.emplace(gpu != nullptr, [] { return internal::ProbeGpuCost(); });
  }
  internal::SceneSize size{cache.size(), 0, cache.structure()};
  for (const CachedObject* object : cache.Objects()) size.triangles += object->mesh.num_triangles();
  std::string reason;
  // A step that calibrates (the GPU probe, a try of a candidate) is setup: the steps after it
  // run the configuration chosen.
  SetupScope setup(&control);
  const internal::Candidate chosen = selector->Choose(size, &reason);
  if (!selector->trying()) setup.End();
  StepRequest concrete = request;
  concrete.method = chosen.method;
  if (chosen.gpu()) {
    concrete.mechanism = chosen.mechanism;
    concrete.resolution = chosen.resolution;
  }
  const auto start = Clock::now();
  auto result = Step(concrete, control);
  if (!result) return result;
  selector->Record(chosen, std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  result->stats.method_reason = std::move(reason);
  return result;
}

// One step: each stage runs only if the requested output needs it.
Result<StepResult> Pipeline::Impl::Step(const StepRequest& request, const StepControl& control) {
  if (auto ok = CheckStepRequest(request); !ok) return ok.error();
  if (request.method == Method::kAuto) return StepAuto(request, control);
  if (IsGpuMethod(request.method) && !gpu) {
    return MakeError(ErrorCode::kUnavailable, "method '" + std::string(ToString(request.method)) +
                                                  "' needs the GPU, and this pipeline has no GL "
                                                  "context");
  }
  StepState state{request, control, {}, {}, {}, 0.0, {}};
  state.result.stats.method = ConfigName(request);
  StageTimer timer(state.result.stats);
  if (auto ran = RunStages(state, timer); !ran) return ran.error();
  timer.Finish();
  state.result.stats.certificate.guaranteed = IsReliable(request.method);
  state.result.stats.certificate.basis = internal::GuaranteeBasis(request);
  return std::move(state.result);
}

// The stages of a concrete method, each entered through EnterStage (progress, cancellation)
// and timed; a stage that stops the step returns its error.
Result<void> Pipeline::Impl::RunStages(StepState& state, StageTimer& timer) {
  const StepRequest& request = state.request;
  auto stage = [&](const char* name, auto&& run) -> Result<void> {
    if (auto ok = EnterStage(state, name); !ok) return ok;
    if (auto ok = run(); !ok) return ok;
    timer.End(name);
    return {};
  };
  auto ok = stage("update", [&]() -> Result<void> {
    cache.RefreshWorld();
    state.objects = cache.Objects();
    state.cull_margin = CullMargin(state);
    return {};
  });
  if (!ok) return ok;
  if (request.method == Method::kExact || request.method == Method::kFcl) {
    if (ok = stage("exact", [&] { return RunWholeScene(state); }); !ok) return ok;
    return {};
  }
  if (ok = stage("object_cull", [&] { return CullObjectsStage(state); }); !ok) return ok;
  if (request.output == Output::kObjectPcs && !IsCpuCulling(request.method)) return {};
  ok = stage("sweep_and_prune", [&]() -> Result<void> {
    PairObjectsStage(state);
    return {};
  });
  if (!ok) return ok;
  if (request.output == Output::kObjectPcs || request.output == Output::kObjectPairs) return {};
  if (request.method == Method::kBvh) {
    const char* name = WantsExact(request.output) ? "exact" : "primitive_cull";
    if (ok = stage(name, [&] { return HierarchyStage(state); }); !ok) return ok;
    return {};
  }
  if (ok = stage("primitive_cull", [&] { return CullPrimitivesStage(state); }); !ok) return ok;
  if (!WantsExact(request.output)) return {};
  if (ok = stage("exact", [&] { return ExactStage(state); }); !ok) return ok;
  return {};
}

Pipeline::Pipeline(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Pipeline::~Pipeline() = default;

Result<std::unique_ptr<Pipeline>> Pipeline::Create(const PipelineOptions& options) {
  auto impl = std::make_unique<Impl>(options);
  if (options.use_gl && !options.use_current_context) {
    auto gl = GlContext::Create(options.platform, options.gpu_device);
    if (!gl.ok()) return gl.error();
    impl->gl = std::move(*gl);
    impl->renderer_name = impl->gl->renderer();
  } else if (options.use_gl) {
    const auto gl = LockGl();
    impl->renderer_name = internal::CurrentGlRenderer();
    if (impl->renderer_name.empty()) {
      return MakeError(ErrorCode::kUnavailable,
                       "use_current_context: no GL context is current on this thread");
    }
  }
  if (options.use_gl)
    impl->gpu = std::make_unique<internal::GpuCuller>(impl->cache.counters(), impl->pool);
  return std::unique_ptr<Pipeline>(new Pipeline(std::move(impl)));
}

Result<void> Pipeline::Apply(std::vector<SceneUpdate> updates,
                             const std::function<std::string(size_t)>& where) {
  return impl_->Apply(std::move(updates), where);
}

namespace {
// Single updates report the model's error as it is, without an update number.
std::string NoPrefix(size_t) { return ""; }
}  // namespace

Result<void> Pipeline::AddObject(uint32_t id, Mesh mesh, Motion motion, const Pose& X_WO) {
  return Apply({far::AddObject{id, std::move(mesh), motion, X_WO}}, NoPrefix);
}
Result<void> Pipeline::RemoveObject(uint32_t id) {
  return Apply({far::RemoveObject{id}}, NoPrefix);
}
Result<void> Pipeline::SetPose(uint32_t id, const Pose& X_WO) {
  return Apply({far::SetPose{id, X_WO}}, NoPrefix);
}
Result<void> Pipeline::SetVertices(uint32_t id, std::vector<Eigen::Vector3d> p_MV) {
  return Apply({far::SetVertices{id, std::move(p_MV)}}, NoPrefix);
}

Result<void> Pipeline::LoadScene(const Scene& scene) {
  std::vector<SceneUpdate> updates;
  for (const SceneObject& object : scene.objects) {
    updates.push_back(far::AddObject{object.id, object.mesh, object.motion, object.X_WO});
  }
  return Apply(std::move(updates), [&](size_t i) { return "objects[" + std::to_string(i) + "]."; });
}

bool MeasureGpuCost() { return internal::ProbeGpuCost().has_value(); }

Result<StepResult> Pipeline::Step(const StepRequest& request, const StepControl& control) {
  return impl_->Step(request, control);
}
int Pipeline::num_objects() const { return impl_->cache.size(); }
int64_t Pipeline::num_triangles() const { return impl_->model.num_triangles(); }
void Pipeline::SetCpuBackground(int max_threads) { impl_->pool.SetBackground(max_threads); }
const SceneCounters& Pipeline::counters() const { return impl_->cache.counters(); }
std::string Pipeline::gl_renderer() const { return impl_->renderer_name; }

}  // namespace far
