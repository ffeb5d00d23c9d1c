#include "scene_cache.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "far/offsets/bounding_offset.h"

namespace far::internal {

static_assert(std::is_nothrow_move_constructible_v<CachedObject>,
              "slots_ grows by moving its objects, not copying them");

std::optional<ObjectSlot> SceneCache::Apply(SceneUpdate update) {
  return std::visit(
      [this](auto& u) -> std::optional<ObjectSlot> {
        using T = std::decay_t<decltype(u)>;
        if constexpr (std::is_same_v<T, AddObject>) {
          ++structure_;
          CachedObject object;
          object.id = u.id;
          object.motion = u.motion;
          object.mesh = std::move(u.mesh);
          object.X_WM = NormalizedPose(u.X_WO).ToIsometry();
          if (!free_slots_.empty()) {
            object.slot = free_slots_.back();
            free_slots_.pop_back();
          } else {
            object.slot = SlotAt(slots_.size());
            slots_.emplace_back();
            ids_.emplace_back();
          }
          RefreshGeometry(object);
          slot_of_id_[u.id] = object.slot;
          ids_[Index(object.slot)] = u.id;
          slots_[Index(object.slot)] = std::move(object);
        } else if constexpr (std::is_same_v<T, RemoveObject>) {
          ++structure_;
          const ObjectSlot slot = slot_of_id_.at(u.id);
          slots_[Index(slot)].reset();
          slot_of_id_.erase(u.id);
          free_slots_.push_back(slot);
          return slot;
        } else if constexpr (std::is_same_v<T, SetPose>) {
          CachedObject& object = At(u.id);
          const Eigen::Isometry3d X_WM = NormalizedPose(u.X_WO).ToIsometry();
          // A pose equal to the current one changes nothing: static-looking rigid objects
          // keep their world vertices.
          if (!X_WM.isApprox(object.X_WM, 0.0)) {
            object.X_WM = X_WM;
            object.world_dirty = true;
          }
        } else {
          CachedObject& object = At(u.id);
          object.mesh.p_MV = std::move(u.p_MV);
          RefreshGeometry(object);
        }
        return std::nullopt;
      },
      update);
}

void SceneCache::RefreshGeometry(CachedObject& object) {
  object.geometry_stamp = next_stamp_++;
  object.world_dirty = true;
}

// Triangles or vertices between two polls of a stopper in the long loops below.
constexpr size_t kPollEvery = 1 << 15;

bool SceneCache::ComputeGpuGeometry(CachedObject& object, StepStopper& stopper) {
  Eigen::AlignedBox3d box_M;
  for (const auto& p : object.mesh.p_MV) box_M.extend(p);
  object.anchor_M = box_M.center();
  double extent = 0;
  for (const auto& p : object.mesh.p_MV)
    extent = std::max(extent, (p - object.anchor_M).cwiseAbs().maxCoeff());
  // A rectangle corner is within one edge length (<= 2 extent) of a vertex.
  object.local_extent = 3.0 * extent;
  object.rect_boxes_M.resize(object.mesh.triangles.size());
  object.rect_box_M.setEmpty();
  for (size_t t = 0; t < object.mesh.triangles.size(); ++t) {
    if (t % kPollEvery == kPollEvery - 1 && stopper.Poll()) return false;
    const auto& tri = object.mesh.triangles[t];
    const Obb rect = TriangleRectangle(object.mesh.p_MV[tri[0]], object.mesh.p_MV[tri[1]],
                                       object.mesh.p_MV[tri[2]]);
    object.rect_boxes_M[t] = ObbAabb(rect);
    object.rect_box_M.extend(object.rect_boxes_M[t]);
  }
  object.gpu_stamp = object.geometry_stamp;
  return true;
}

StopReason SceneCache::RefreshGpuGeometry(ThreadPool& pool, const StepControl& control) {
  std::vector<CachedObject*> stale;
  for (auto& object : slots_) {
    if (object && object->gpu_stamp != object->geometry_stamp) stale.push_back(&*object);
  }
  StepStopper stopper(&control);
  pool.ParallelFor(stale.size(), 1, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end && !stopper.Poll(); ++i) ComputeGpuGeometry(*stale[i], stopper);
  });
  return stopper.reason();
}

namespace {

// Whether FlushTinyCoordinates changes `c` (to +0: -0 is flushed too, so that the world
// vertices are the same bits whether or not p_MV stands in for them).
bool FlushChanges(double c) {
  return std::abs(c) < kTinyWorldCoordinate && (c != 0.0 || std::signbit(c));
}

// Places one object's vertices in the world. The identity pose maps each vertex to itself
// exactly (1 x + 0 y + 0 z + 0 is x): a deformable object that keeps it (the usual case) reads
// its world vertices from p_MV unless one needs flushing, and is only scanned for its box.
void PlaceInWorld(CachedObject& object) {
  const std::vector<Eigen::Vector3d>& p_MV = object.mesh.p_MV;
  object.box_W.setEmpty();
  if (object.X_WM.matrix() == Eigen::Matrix4d::Identity()) {
    bool flushes = false;
    for (const Eigen::Vector3d& p : p_MV) {
      object.box_W.extend(p);
      flushes = flushes || FlushChanges(p.x()) || FlushChanges(p.y()) || FlushChanges(p.z());
    }
    object.world_is_model = !flushes;
    if (object.world_is_model) {
      object.placed_WV = {};
      return;
    }
  }
  object.world_is_model = false;
  const Eigen::Matrix<double, 3, 4> X_WM = object.X_WM.matrix().topRows<3>();
  object.placed_WV.resize(p_MV.size());
  object.box_W.setEmpty();
  for (size_t v = 0; v < p_MV.size(); ++v) {
    object.placed_WV[v] = WorldVertex(X_WM, p_MV[v]);
    object.box_W.extend(object.placed_WV[v]);
  }
}

// Below this many vertices to place in all, a step places them on its own thread: waking the
// pool would cost more than it saves.
constexpr size_t kParallelPlacement = 1 << 15;

}  // namespace

void SceneCache::RefreshWorld(ThreadPool& pool) {
  std::vector<CachedObject*> dirty;
  size_t vertices = 0;
  for (auto& slot : slots_) {
    if (!slot || !slot->world_dirty) continue;
    dirty.push_back(&*slot);
    vertices += slot->mesh.p_MV.size();
  }
  const size_t grain = vertices < kParallelPlacement ? dirty.size() : 1;
  pool.ParallelFor(dirty.size(), grain, [&dirty](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) PlaceInWorld(*dirty[i]);
  });
  for (CachedObject* object : dirty) object->world_dirty = false;
  counters_.world_updates += static_cast<int64_t>(dirty.size());
}

StopReason SceneCache::RefreshHierarchies(std::span<const ObjectSlot> slots, ThreadPool& pool,
                                          const StepControl& control) {
  std::vector<CachedObject*> builds, refits;
  for (ObjectSlot slot : slots) {
    CachedObject& object = *slots_[Index(slot)];
    if (object.bvh_stamp == object.geometry_stamp) continue;
    (object.bvh.empty() ? builds : refits).push_back(&object);
  }
  // A hierarchy is up to date once built or refit whole; one abandoned is left empty.
  StepStopper stopper(&control);
  const auto done = [](CachedObject& object) {
    if (!object.bvh.empty() || object.mesh.triangles.empty())
      object.bvh_stamp = object.geometry_stamp;
  };
  if (!builds.empty()) {
    // One-off work: later steps of these objects do not repeat it.
    SetupScope setup(&control);
    pool.ParallelFor(builds.size(), 1, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end && !stopper.Poll(); ++i) {
        builds[i]->bvh.Build(builds[i]->mesh.p_MV, builds[i]->mesh.triangles, &stopper);
        done(*builds[i]);
      }
    });
  }
  pool.ParallelFor(refits.size(), 1, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end && !stopper.Poll(); ++i) {
      (void)refits[i]->bvh.Refit(refits[i]->mesh.p_MV, refits[i]->mesh.triangles, &stopper);
      done(*refits[i]);
    }
  });
  return stopper.reason();
}

std::vector<const CachedObject*> SceneCache::Objects() const {
  std::vector<const CachedObject*> objects(slots_.size(), nullptr);
  for (size_t s = 0; s < slots_.size(); ++s) {
    if (slots_[s]) objects[s] = &*slots_[s];
  }
  return objects;
}

std::vector<WorldObjectView> SceneCache::WorldViews() const {
  std::vector<WorldObjectView> world(slots_.size());
  for (size_t s = 0; s < slots_.size(); ++s) {
    if (slots_[s]) world[s] = {slots_[s]->p_WV(), slots_[s]->mesh.triangles};
  }
  return world;
}

}  // namespace far::internal
