#include "compute_stage.h"

#include <map>
#include <mutex>
#include <string>
#include <utility>

#include "compute_self_check.h"

#include "far/gpu/culling_renderer.h"
#include "far/pairs/sweep_and_prune.h"
#include "far/pairs/triangle_bvh.h"

namespace far::internal {
namespace {

// The self-check's verdict, once per renderer and process: the driver, not the session,
// decides it.
Result<void> CheckedOnThisDriver(ComputeCollider& collider) {
  static std::mutex mutex;
  static std::map<std::string, Result<void>> verdicts;
  const std::string renderer = CurrentGlRenderer();
  std::lock_guard lock(mutex);
  if (auto it = verdicts.find(renderer); it != verdicts.end()) return it->second;
  Result<void> verdict = SelfCheckComputeCollider(collider);
  verdicts.emplace(renderer, verdict);
  return verdict;
}

// How often a deformable object's topology is checked: every this many changes of its
// vertices. A check refits the object's hierarchy on the CPU, O(n), which the GPU does every
// step: paper-leaves' checks took 0.013 ms a step at one in 64 (about 2 leaves a step) and
// 0.010 ms at one in 128 (2 s at 60 steps a second), a fiftieth of the gpu step's CPU side.
constexpr uint32_t kLooseCheckEvery = 128;
// Checks of fewer triangles than this in one step run on the calling thread (about 0.1 ms):
// waking the pool cost paper-leaves' 2 or 3 checks a step 0.039 ms instead of 0.013.
constexpr size_t kPoolCheckTriangles = 8192;

// The topology TriangleBvh built, without its boxes.
void TakeTopology(const TriangleBvh& bvh, std::vector<ComputeNode>& nodes,
                  std::vector<uint32_t>& order) {
  nodes.clear();
  nodes.reserve(bvh.nodes().size());
  for (const TriangleBvh::Node& node : bvh.nodes()) nodes.push_back({node.first, node.count});
  order = bvh.order();
}

}  // namespace

// Every live object gets its topology once (the layout on the GPU then changes only when
// objects come or go): TriangleBvh's, built from the vertices it has now, without its boxes.
StopReason ComputeStage::BuildTopologies(std::span<const CachedObject* const> objects,
                                         const StepControl& control) {
  if (slots_.size() < objects.size()) slots_.resize(objects.size());
  std::vector<size_t> missing;
  for (size_t s = 0; s < objects.size(); ++s) {
    if (objects[s] != nullptr && !slots_[s]) missing.push_back(s);
  }
  if (missing.empty()) return StopReason::kNone;
  SetupScope setup(&control);  // one-off work: later steps of these objects do not repeat it
  StepStopper stopper(&control);
  std::vector<std::optional<SlotState>> built(missing.size());
  pool_.ParallelFor(missing.size(), 1, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end && !stopper.Poll(); ++i) {
      const CachedObject& object = *objects[missing[i]];
      TriangleBvh bvh;
      if (!bvh.Build(object.mesh.p_MV, object.mesh.triangles, &stopper)) return;
      SlotState state;
      TakeTopology(bvh, state.nodes, state.order);
      if (object.motion == Motion::kDeformable) state.shape = std::move(bvh);
      built[i] = std::move(state);
    }
  });
  if (stopper.stopped()) return stopper.reason();
  for (size_t i = 0; i < missing.size(); ++i) {
    built[i]->topology_key = next_key_++;
    slots_[missing[i]] = std::move(built[i]);
  }
  return StopReason::kNone;
}

// A deformable object's topology was built for its first shape: once it has deformed far, its
// refit boxes grow loose and the traversal meets more of them. Every kLooseCheckEvery changes
// of its vertices (staggered by slot, so that objects that deform together are not all checked
// on one step), its CPU hierarchy is refit by TriangleBvh's rule, and when that rule rebuilds
// (boxes' summed surface area past twice the built one) the GPU gets the new topology.
StopReason ComputeStage::RebuildLooseTopologies(std::span<const CachedObject* const> objects,
                                                const StepControl& control) {
  std::vector<size_t> due;
  for (size_t s = 0; s < objects.size(); ++s) {
    if (objects[s] == nullptr || objects[s]->motion != Motion::kDeformable || !slots_[s]) continue;
    // geometry_stamp is the last step's until Filter hands the new vertices over (a step
    // stopped before that counts its change twice: its check comes a step early).
    SlotState& state = *slots_[s];
    if (state.geometry_stamp == objects[s]->geometry_stamp) continue;
    if ((++state.deformations + s) % kLooseCheckEvery == 0) due.push_back(s);
  }
  if (due.empty()) return StopReason::kNone;
  StepStopper stopper(&control);
  std::vector<uint8_t> rebuilt(due.size(), 0);
  size_t due_triangles = 0;
  for (size_t s : due) due_triangles += objects[s]->mesh.triangles.size();
  const auto check = [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end && !stopper.Poll(); ++i) {
      const Mesh& mesh = objects[due[i]]->mesh;
      rebuilt[i] = slots_[due[i]]->shape.Refit(mesh.p_MV, mesh.triangles, &stopper);
    }
  };
  if (due_triangles < kPoolCheckTriangles) {
    check(0, due.size());
  } else {
    pool_.ParallelFor(due.size(), 1, check);
  }
  // A rebuild that was stopped leaves its hierarchy empty: the slot keeps its old topology, and
  // its next check builds afresh (Refit of an empty hierarchy builds).
  for (size_t i = 0; i < due.size(); ++i) {
    SlotState& state = *slots_[due[i]];
    if (!rebuilt[i] || state.shape.empty()) continue;
    TakeTopology(state.shape, state.nodes, state.order);
    state.topology_key = next_key_++;
    ++topologies_rebuilt_;
  }
  return stopper.reason();
}

Result<ComputeAnswer> ComputeStage::Filter(std::span<const CachedObject* const> objects,
                                           double object_margin, double slack,
                                           std::optional<double> distance,
                                           const StepControl& control, StopReason* stopped) {
  topologies_rebuilt_ = 0;
  *stopped = BuildTopologies(objects, control);
  if (*stopped == StopReason::kNone) *stopped = RebuildLooseTopologies(objects, control);
  if (*stopped != StopReason::kNone) return ComputeAnswer{};
  if (auto made = MakeCollider(control); !made) return made.error();
  if (!trusted_) return trusted_.error();
  std::vector<ComputeObject> views(objects.size());
  for (size_t s = 0; s < objects.size(); ++s) {
    if (objects[s] == nullptr) continue;
    const CachedObject& object = *objects[s];
    SlotState& state = *slots_[s];
    const Eigen::Matrix<double, 3, 4> X_WM = object.X_WM.matrix().topRows<3>();
    if (state.world_key == 0 || state.geometry_stamp != object.geometry_stamp ||
        state.X_WM != X_WM) {
      state.geometry_stamp = object.geometry_stamp;
      state.X_WM = X_WM;
      state.world_key = next_key_++;
    }
    views[s] = {object.p_WV(),
                object.mesh.triangles,
                state.nodes,
                state.order,
                state.topology_key,
                state.world_key,
                SweepAndPrune::GrownBox(object.box_W, object_margin)};
    // A posed object's world vertices are WorldVertex(X_WM, p_MV) (SceneCache::RefreshWorld):
    // the collider may place them on the GPU from the pose.
    if (object.X_WM.matrix() != Eigen::Matrix4d::Identity()) {
      views[s].p_MV = object.mesh.p_MV;
      views[s].X_WM = X_WM;
      views[s].model_key = object.geometry_stamp;
    }
  }
  ComputeQuery query;
  query.objects = views;
  query.slack = slack;
  query.distance = distance.has_value();
  if (distance) query.max_distance = *distance;
  return Run(query);
}

Result<void> ComputeStage::MakeCollider(const StepControl& control) {
  if (collider_ || batched_id_) return {};
  SetupScope setup(&control);  // compiling the kernels and checking them is one-off work
  if (batcher_ == nullptr) {
    auto made = ComputeCollider::Create();
    if (!made) return made.error();
    collider_ = std::move(*made);
    trusted_ = CheckedOnThisDriver(*collider_);
    return {};
  }
  auto added = batcher_->AddCollider();
  if (!added) return added.error();
  batched_id_ = *added;
  trusted_ = batcher_->WithCollider(*batched_id_, CheckedOnThisDriver);
  return {};
}

Result<ComputeAnswer> ComputeStage::Run(const ComputeQuery& query) {
  if (batched_id_) return batcher_->Run(*batched_id_, query);
  return collider_->Run(query);
}

ComputeStage::~ComputeStage() {
  if (batched_id_) batcher_->RemoveCollider(*batched_id_);
}

void ComputeStage::RemoveSlot(ObjectSlot slot) {
  if (Index(slot) < slots_.size()) slots_[Index(slot)].reset();
}

}  // namespace far::internal
