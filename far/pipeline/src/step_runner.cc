#include "step_runner.h"

#include <algorithm>
#include <chrono>
#include <set>
#include <string>
#include <utility>

#include "geometry_stage.h"
#include "guarantee.h"
#include "stop_error.h"

#include "far/base/limits.h"
#include "far/model/slot_ids.h"
#include "far/pairs/bvh_stage.h"
#include "far/pairs/exact_stage.h"
#include "far/pairs/internal/pair_sort.h"
#include "far/pipeline/internal/auto_selector.h"

namespace far::internal {
namespace {

using Clock = std::chrono::steady_clock;

// The methods that cull by pairs (the CPU ones and gpu): every object goes to sweep-and-prune,
// the object PCS is the objects in some pair.
bool IsCpuCulling(Method method) {
  return method == Method::kAabb || method == Method::kBvh || method == Method::kGpu;
}

bool WantsExact(Output output) {
  return output == Output::kContacts || output == Output::kDistancePairs;
}

// Times the stages of one step into its stats.
class StageTimer {
 public:
  explicit StageTimer(StepStats& stats) : stats_(stats) {}
  void End(Stage stage) {
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

// A step's answer while its stages run: objects by slot. Arrays by slot are indexed by Index().
struct SlotAnswer {
  std::vector<ObjectSlot> pcs_objects;
  std::vector<SlotPair> object_pairs;
  std::vector<std::vector<uint32_t>> pcs_primitives;  // by slot: sorted triangles
  std::vector<SlotContact> contacts;
  std::vector<SlotDistancePair> distance_pairs;
};

// What the stages of one step hand each other.
struct StepState {
  const StepRequest& request;
  const StepControl& control;
  std::vector<const CachedObject*> objects;    // by slot; null: a free slot
  std::vector<WorldObjectView> views;          // by slot
  std::vector<uint8_t> object_alive;           // by slot: in the object PCS
  std::vector<std::vector<uint32_t>> subsets;  // by slot: its triangles in the primitive PCS
  double cull_margin = 0;                      // CullMargin, once the world boxes are known
  ComputeAnswer computed;                      // gpu: the GPU's filtered pairs
  SlotAnswer answer;
  StepStats stats;
};

// The start of a stage: progress for the caller, and the check that the step may go on.
Result<void> EnterStage(const StepState& state, Stage stage) {
  if (state.control.on_stage) state.control.on_stage(stage);
  const StopReason reason = state.control.Check();
  if (reason != StopReason::kNone) return StopError(reason, stage, state.control);
  return {};
}

// The configuration a request runs: "bvh", "far/id-buffer/1024".
std::string ConfigName(const StepRequest& request) {
  return Candidate{request.method, request.mechanism, request.resolution}.Name();
}

// Sorts and deduplicates a list.
void SortUnique(std::vector<uint32_t>& values) {
  std::sort(values.begin(), values.end());
  values.erase(std::unique(values.begin(), values.end()), values.end());
}

// The exact answer of a stage, into the step's answer and stats.
void TakeExact(ExactResult exact, StepState& state) {
  state.answer.contacts = std::move(exact.contacts);
  state.answer.distance_pairs = std::move(exact.distance_pairs);
  state.stats.pairs_considered = static_cast<int64_t>(exact.pairs_considered);
  state.stats.pairs_tested = static_cast<int64_t>(exact.pairs_tested);
}

// How much the CPU culls (sweep-and-prune, the aabb method's triangle boxes) grow boxes: 0 for
// contacts (closed boxes that touch overlap), CullSlack for a distance query, so that they drop
// no pair the exact tests would report.
double CullMargin(const StepState& state) {
  if (!state.request.distance) return 0.0;
  double magnitude = 0;
  for (const CachedObject* object : state.objects) {
    if (object == nullptr || object->box_W.isEmpty()) continue;
    magnitude = std::max({magnitude, object->box_W.min().cwiseAbs().maxCoeff(),
                          object->box_W.max().cwiseAbs().maxCoeff()});
  }
  return CullSlack(*state.request.distance, magnitude);
}

// The AABB baseline's primitive PCS: per object of a candidate pair, the triangles whose box
// overlaps the partner object's box grown by the cull margin. A large scene takes seconds here:
// the control is checked every kTrianglesPerCheck triangles.
Result<std::vector<std::vector<uint32_t>>> TrianglesInPartnerBoxes(const StepState& state) {
  constexpr size_t kTrianglesPerCheck = 1 << 16;
  std::vector<std::vector<uint32_t>> subsets(state.objects.size());
  size_t unchecked = 0;
  for (const SlotPair& pair : state.answer.object_pairs) {
    for (auto [self, other] :
         {std::pair(pair.object_a, pair.object_b), std::pair(pair.object_b, pair.object_a)}) {
      Eigen::AlignedBox3d partner = state.objects[Index(other)]->box_W;
      partner.min().array() -= state.cull_margin;
      partner.max().array() += state.cull_margin;
      const CachedObject& object = *state.objects[Index(self)];
      for (size_t t = 0; t < object.mesh.triangles.size(); ++t) {
        if (++unchecked == kTrianglesPerCheck) {
          unchecked = 0;
          if (const StopReason reason = state.control.Check(); reason != StopReason::kNone)
            return StopError(reason, Stage::kPrimitiveCull, state.control);
        }
        Eigen::AlignedBox3d box;
        for (uint32_t v : object.mesh.triangles[t]) box.extend(object.p_WV()[v]);
        if (box.intersects(partner)) subsets[Index(self)].push_back(static_cast<uint32_t>(t));
      }
    }
  }
  for (auto& subset : subsets) SortUnique(subset);
  return subsets;
}

// The step's answer by id: where ids come back (far/model/slot_ids.h), once.
void FillAnswer(StepState& state, const SceneCache& cache, StepResult& result) {
  const SlotIds ids(cache.ids());
  SlotAnswer& answer = state.answer;
  for (ObjectSlot slot : answer.pcs_objects) result.pcs_objects.push_back(ids(slot));
  if (!std::is_sorted(result.pcs_objects.begin(), result.pcs_objects.end()))
    std::sort(result.pcs_objects.begin(), result.pcs_objects.end());
  result.object_pairs = ids.WithIds(answer.object_pairs);
  for (size_t s = 0; s < answer.pcs_primitives.size(); ++s) {
    if (!answer.pcs_primitives[s].empty())
      result.pcs_primitives[ids(SlotAt(s))] = std::move(answer.pcs_primitives[s]);
  }
  result.contacts = ids.WithIds(answer.contacts);
  result.distance_pairs = ids.WithIds(answer.distance_pairs);
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
}

// The stages of one step on a world (RunStep's).
class Stages {
 public:
  Stages(StepWorld& world, StepState& state) : world_(world), state_(state) {}

  /// The stages, then the answer by id.
  Result<StepResult> Run();

 private:
  Result<void> RunStages(StageTimer& timer);
  Result<void> RunWholeScene();
  Result<void> CullObjects();
  void PairObjects();
  // The step's object pairs (sorted), their count, and for CPU culling the object PCS.
  void TakeObjectPairs(std::vector<SlotPair> pairs);
  Result<void> CullPrimitives();
  Result<void> TestExactly();
  Result<void> DescendHierarchiesStage();
  BvhResult DescendHierarchies(bool run_exact);
  Result<void> FilterOnGpu();
  Result<void> DecideUndecided();

  StepWorld& world_;
  StepState& state_;
};

// The reference (every triangle pair) and FCL answer in one stage, without culling.
Result<void> Stages::RunWholeScene() {
  ExactResult exact;
  if (state_.request.method == Method::kExact) {
    if (const uint64_t pairs = BruteForcePairs(state_.views); pairs > kMaxBruteForcePairs) {
      return MakeError(ErrorCode::kLimitExceeded,
                       "method 'exact' is the brute-force reference: this scene has " +
                           std::to_string(pairs) + " cross-object triangle pairs, over its limit " +
                           std::to_string(kMaxBruteForcePairs) +
                           "; 'bvh' gives the same exact answer");
    }
    exact =
        BruteForceReference(state_.views, state_.request.distance, world_.pool, &state_.control);
  } else {
    std::vector<FclCollider::Object> fcl_objects;
    for (const CachedObject* object : state_.objects) {
      if (object != nullptr)
        fcl_objects.push_back({object->slot, object->geometry_stamp, &object->mesh, object->X_WM});
    }
    FclCollider::CollideStats fcl_stats;
    exact.contacts = world_.fcl.Collide(fcl_objects, &fcl_stats, &state_.control);
    exact.pairs_considered = fcl_stats.triangle_pairs_considered;
    exact.pairs_tested = fcl_stats.triangle_tests;
    exact.stopped = fcl_stats.stopped;
    state_.stats.object_pairs = static_cast<int64_t>(fcl_stats.object_pairs);
  }
  if (exact.stopped != StopReason::kNone)
    return StopError(exact.stopped, Stage::kExact, state_.control);
  TakeExact(std::move(exact), state_);
  return {};
}

// Object-level culling -> object PCS (CPU culling: every object goes on to sweep-and-prune).
Result<void> Stages::CullObjects() {
  if (IsGpuMethod(state_.request.method)) {
    if (const StopReason stop = world_.cache.RefreshGpuGeometry(world_.pool, state_.control);
        stop != StopReason::kNone) {
      return StopError(stop, Stage::kObjectCull, state_.control);
    }
    std::vector<ObjectSlot> live;
    for (const CachedObject* object : state_.objects) {
      if (object != nullptr) live.push_back(object->slot);
    }
    if (const StopReason stop = world_.cache.RefreshHierarchies(live, world_.pool, state_.control);
        stop != StopReason::kNone) {
      return StopError(stop, Stage::kObjectCull, state_.control);
    }
    auto alive =
        world_.gpu->CullObjects(state_.request, state_.objects, state_.stats, state_.control);
    if (!alive) return alive.error();
    state_.object_alive = std::move(*alive);
  } else {
    state_.object_alive.assign(state_.objects.size(), 0);
    for (size_t s = 0; s < state_.objects.size(); ++s)
      state_.object_alive[s] = state_.objects[s] != nullptr;
  }
  if (IsCpuCulling(state_.request.method)) return {};  // its PCS comes from the pairs
  for (size_t s = 0; s < state_.objects.size(); ++s) {
    if (state_.object_alive[s]) state_.answer.pcs_objects.push_back(SlotAt(s));
  }
  return {};
}

// Sweep-and-prune on the PCS objects' AABBs (margin CullMargin for distance queries).
void Stages::PairObjects() {
  std::vector<SlotBox> boxes;
  for (size_t s = 0; s < state_.objects.size(); ++s) {
    if (state_.object_alive[s]) boxes.push_back({SlotAt(s), state_.objects[s]->box_W});
  }
  TakeObjectPairs(world_.sap.Update(boxes, state_.cull_margin));
}

void Stages::TakeObjectPairs(std::vector<SlotPair> pairs) {
  state_.answer.object_pairs = std::move(pairs);
  state_.stats.object_pairs = static_cast<int64_t>(state_.answer.object_pairs.size());
  // I-COLLIDE: the CPU culling methods' PCS is the set of objects in some overlapping pair.
  if (IsCpuCulling(state_.request.method))
    state_.answer.pcs_objects = SlotsInPairs(state_.answer.object_pairs);
}

// The objects in some candidate pair, with their hierarchies brought up to date, and the
// simultaneous descent of each pair's hierarchies: candidate triangles (near a partner's
// triangle, within D), and the exact answer when `run_exact`.
BvhResult Stages::DescendHierarchies(bool run_exact) {
  const std::vector<ObjectSlot> paired = SlotsInPairs(state_.answer.object_pairs);
  if (const StopReason stop = world_.cache.RefreshHierarchies(paired, world_.pool, state_.control);
      stop != StopReason::kNone) {
    // An object may be left without a hierarchy: nothing may descend it.
    BvhResult stopped;
    stopped.exact.stopped = stop;
    return stopped;
  }
  std::vector<ObjectHierarchy> hierarchies(state_.objects.size());
  for (ObjectSlot slot : paired) {
    const CachedObject& object = *state_.objects[Index(slot)];
    hierarchies[Index(slot)] = {&object.bvh, object.X_WM};
  }
  BvhQuery query;
  query.objects = state_.views;
  query.object_pairs = state_.answer.object_pairs;
  query.max_distance = state_.request.distance;
  query.want_distance_pairs = state_.request.output == Output::kDistancePairs;
  query.control = &state_.control;
  query.hierarchies = hierarchies;
  query.run_exact = run_exact;
  return RunBvhTests(query, world_.pool);
}

// Sub-object culling of the objects in candidate pairs -> primitive PCS.
Result<void> Stages::CullPrimitives() {
  if (IsGpuMethod(state_.request.method)) {
    // The GPU draws only the triangles the hierarchies found near a partner: elsewhere there is
    // nothing for it to prune.
    BvhResult near = DescendHierarchies(/*run_exact=*/false);
    if (near.exact.stopped != StopReason::kNone)
      return StopError(near.exact.stopped, Stage::kPrimitiveCull, state_.control);
    const std::vector<ObjectSlot> paired = SlotsInPairs(state_.answer.object_pairs);
    auto subsets = world_.gpu->CullPrimitives(state_.request, state_.objects, paired,
                                              near.candidates, state_.stats, state_.control);
    if (!subsets) return subsets.error();
    state_.subsets = std::move(*subsets);
  } else {
    auto subsets = TrianglesInPartnerBoxes(state_);
    if (!subsets) return subsets.error();
    state_.subsets = std::move(*subsets);
  }
  // The PCS of the paired objects (the others' subsets are empty).
  state_.answer.pcs_primitives = state_.subsets;
  return {};
}

// Exact tests on the CPU pool: PCS triangles of candidate object pairs.
Result<void> Stages::TestExactly() {
  ExactQuery query;
  query.objects = state_.views;
  query.object_pairs = state_.answer.object_pairs;
  query.triangle_subsets = state_.subsets;
  // The exact stage widens its prefilter by D only when it reports distance pairs.
  if (state_.request.output == Output::kDistancePairs) query.max_distance = state_.request.distance;
  query.control = &state_.control;
  ExactResult exact = RunExactTests(query, world_.pool);
  if (exact.stopped != StopReason::kNone)
    return StopError(exact.stopped, Stage::kExact, state_.control);
  TakeExact(std::move(exact), state_);
  return {};
}

// The bvh method after sweep-and-prune: the descent, with the exact tests at the leaves when the
// output needs them; the triangles met on the way are the primitive PCS.
Result<void> Stages::DescendHierarchiesStage() {
  const bool run_exact = WantsExact(state_.request.output);
  BvhResult found = DescendHierarchies(run_exact);
  if (found.exact.stopped != StopReason::kNone) {
    return StopError(found.exact.stopped, run_exact ? Stage::kExact : Stage::kPrimitiveCull,
                     state_.control);
  }
  state_.answer.pcs_primitives = std::move(found.candidates);
  state_.stats.descent = found.counters;
  TakeExact(std::move(found.exact), state_);
  return {};
}

// The gpu method's GPU stage: the GPU finds the object pairs (the pairs sweep-and-prune finds
// for the other methods), descends each pair's hierarchies and filters the triangle pairs
// (compute_stage.h); the primitive PCS is the triangles of the pairs it did not prove apart
// (a distance query: of every pair within the slack).
Result<void> Stages::FilterOnGpu() {
  const StepRequest& request = state_.request;
  const bool distance = request.distance.has_value() && (request.output == Output::kDistancePairs ||
                                                         request.output == Output::kPrimitivePcs);
  StopReason stopped = StopReason::kNone;
  auto computed = world_.compute->Filter(
      state_.objects, state_.cull_margin, distance ? state_.cull_margin : 0.0,
      distance ? request.distance : std::nullopt, state_.control, &stopped);
  if (stopped != StopReason::kNone)
    return StopError(stopped, Stage::kPrimitiveCull, state_.control);
  if (!computed) return computed.error();
  state_.computed = std::move(*computed);
  // The object pairs, found on the GPU as sweep-and-prune finds them for the other methods.
  TakeObjectPairs(std::move(state_.computed.object_pairs));
  state_.stats.bytes_uploaded += state_.computed.bytes_uploaded;
  state_.stats.pairs_considered = state_.computed.box_pairs;
  const ComputeAnswer& answer = state_.computed;
  state_.stats.gpu_filter = {answer.box_pairs,
                             answer.float_decided,
                             answer.double_decided,
                             static_cast<int64_t>(answer.undecided.size()),
                             answer.distance_culled,
                             answer.runs,
                             world_.compute->topologies_rebuilt(),
                             answer.vertices_placed,
                             answer.gpu_refit_ms,
                             answer.gpu_traverse_ms,
                             answer.gpu_filter_ms};
  // As the raster methods report their views: CPU issuing, CPU waiting and reading, GPU time.
  state_.stats.gl_prepare_ms += answer.cpu_submit_ms;
  state_.stats.gl_passes_ms += answer.cpu_wait_ms;
  state_.stats.gl_gpu_ms += answer.gpu_refit_ms + answer.gpu_traverse_ms + answer.gpu_filter_ms;
  // The primitive PCS, from the GPU's bits (sorted by slot; none when no pair was run).
  std::vector<std::vector<uint32_t>> pcs = std::move(state_.computed.pcs);
  pcs.resize(state_.objects.size());
  state_.answer.pcs_primitives = std::move(pcs);
  return {};
}

// The gpu method's exact stage: the CPU's exact predicates on the pairs the GPU left undecided,
// and the pairs it proved crossing (at distance 0 in a distance query).
Result<void> Stages::DecideUndecided() {
  TrianglePairQuery query;
  query.objects = state_.views;
  query.pairs = state_.computed.undecided;
  query.known_apart = state_.computed.proven_apart;
  if (state_.request.output == Output::kDistancePairs) query.max_distance = state_.request.distance;
  query.want_distance_pairs = state_.request.output == Output::kDistancePairs;
  query.control = &state_.control;
  ExactResult exact = RunExactTestsOnPairs(query, world_.pool);
  if (exact.stopped != StopReason::kNone)
    return StopError(exact.stopped, Stage::kExact, state_.control);
  exact.pairs_considered = static_cast<size_t>(state_.computed.box_pairs);
  // The crossing pairs are most of a step's contacts (all of paper-leaves' 4,900 or so): they
  // are not copied, the CPU's few are appended to them.
  std::vector<SlotContact> crossing = std::move(state_.computed.crossing);
  if (query.want_distance_pairs) {
    for (const SlotContact& pair : crossing) exact.distance_pairs.push_back({pair, 0.0});
  }
  crossing.insert(crossing.end(), exact.contacts.begin(), exact.contacts.end());
  exact.contacts = std::move(crossing);
  SortPairs(exact.contacts);
  SortPairs(exact.distance_pairs);
  TakeExact(std::move(exact), state_);
  return {};
}

Result<StepResult> Stages::Run() {
  StageTimer timer(state_.stats);
  if (auto ran = RunStages(timer); !ran) return ran.error();
  StepResult result;
  FillAnswer(state_, world_.cache, result);
  if (state_.request.method == Method::kExact || state_.request.method == Method::kFcl) {
    DeriveCullingOutputs(result);
    // FCL's object pairs are its broadphase's; exact has no candidates: those of its answer.
    if (state_.request.method == Method::kExact)
      state_.stats.object_pairs = static_cast<int64_t>(result.object_pairs.size());
  }
  // The geometry stage reads the answer by id (its arrays run parallel to the result's).
  if (state_.request.geometry && WantsExact(state_.request.output)) {
    if (auto ok = EnterStage(state_, Stage::kGeometry); !ok) return ok.error();
    ComputeGeometry(state_.views, world_.cache.ids(), world_.pool, world_.closedness, result);
    timer.End(Stage::kGeometry);
  }
  timer.Finish();
  result.stats = std::move(state_.stats);
  return result;
}

// The stages of a concrete method, each entered through EnterStage (progress, cancellation)
// and timed; a stage that stops the step returns its error.
Result<void> Stages::RunStages(StageTimer& timer) {
  const StepRequest& request = state_.request;
  auto stage = [&](Stage name, auto&& run) -> Result<void> {
    if (auto ok = EnterStage(state_, name); !ok) return ok;
    if (auto ok = run(); !ok) return ok;
    timer.End(name);
    return {};
  };
  auto ok = stage(Stage::kUpdate, [&]() -> Result<void> {
    world_.cache.RefreshWorld(world_.pool);
    state_.objects = world_.cache.Objects();
    state_.views = world_.cache.WorldViews();
    state_.cull_margin = CullMargin(state_);
    return {};
  });
  if (ok && (request.method == Method::kExact || request.method == Method::kFcl)) {
    ok = stage(Stage::kExact, [&] { return RunWholeScene(); });
  } else if (ok) {
    ok = stage(Stage::kObjectCull, [&] { return CullObjects(); });
    const bool pairs = request.output != Output::kObjectPcs || IsCpuCulling(request.method);
    const bool primitives =
        request.output != Output::kObjectPcs && request.output != Output::kObjectPairs;
    // The gpu method finds its object pairs on the GPU, in its primitive_cull stage.
    const bool gpu_pairs = primitives && request.method == Method::kGpu;
    if (ok && pairs && !gpu_pairs) {
      ok = stage(Stage::kSweepAndPrune, [&]() -> Result<void> {
        PairObjects();
        return {};
      });
    }
    if (ok && pairs && gpu_pairs) {
      ok = stage(Stage::kPrimitiveCull, [&] { return FilterOnGpu(); });
      if (ok && WantsExact(request.output))
        ok = stage(Stage::kExact, [&] { return DecideUndecided(); });
    } else if (ok && pairs && primitives && request.method == Method::kBvh) {
      const Stage name = WantsExact(request.output) ? Stage::kExact : Stage::kPrimitiveCull;
      ok = stage(name, [&] { return DescendHierarchiesStage(); });
    } else if (ok && pairs && primitives) {
      ok = stage(Stage::kPrimitiveCull, [&] { return CullPrimitives(); });
      if (ok && WantsExact(request.output))
        ok = stage(Stage::kExact, [&] { return TestExactly(); });
    }
  }
  return ok;
}

}  // namespace

StepWorld::StepWorld(ThreadPool& pool, bool with_gpu, double gl_batch_ms,
                     ComputeBatcher* compute_batcher)
    : pool(pool) {
  if (with_gpu) {
    gpu = std::make_unique<GpuCuller>(cache.counters(), pool, gl_batch_ms);
    compute = std::make_unique<ComputeStage>(pool, compute_batcher);
  }
}

void StepWorld::Apply(SceneUpdate update) {
  const std::optional<ObjectSlot> freed = cache.Apply(std::move(update));
  if (!freed) return;
  if (gpu) gpu->RemoveSlot(*freed);
  if (compute) compute->RemoveSlot(*freed);
  fcl.Remove(*freed);
  closedness.Forget(Index(*freed));
}

Result<StepResult> RunStep(StepWorld& world, const StepRequest& request,
                           const StepControl& control) {
  StepState state{request, control, {}, {}, {}, {}, 0.0, {}, {}, {}};
  state.stats.method = ConfigName(request);
  auto result = Stages(world, state).Run();
  if (!result) return result;
  result->stats.certificate.guaranteed = IsReliable(request.method);
  result->stats.certificate.basis = GuaranteeBasis(request);
  return result;
}

}  // namespace far::internal
