#include "fcl_collider.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <thread>
#include <unordered_set>

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/detail/traversal/collision/mesh_collision_traversal_node.h>
#include <fcl/narrowphase/detail/traversal/collision_node.h>

namespace far::internal {
namespace {

using Model = fcl::BVHModel<fcl::OBBRSSd>;

std::vector<fcl::Vector3d> Points(const Mesh& mesh) {
  return std::vector<fcl::Vector3d>(mesh.p_MV.begin(), mesh.p_MV.end());
}

// A model built on a thread of its own. FCL's build cannot be interrupted, and takes seconds
// for a large object (10 s for 600K triangles on a loaded 2-core machine): the step waits for it
// with checks of its control, and a step that must stop returns while the build goes on; the
// next step takes the model when it is done. The thread holds the only other reference to
// the job and copies of the mesh, so that neither a removed object nor a closed collider waits
// for it.
struct BuildJob {
  std::mutex mutex;
  std::condition_variable finished;
  std::shared_ptr<Model> model;  // set when built
  uint64_t stamp = 0;            // the geometry it was built from

  // Copies `mesh` (in parts, with checks of `control` between them: copying 2M triangles into
  // fresh memory took half a second on the development machine) and starts the build; null when
  // the control said stop first (`stop` says why).
  static std::shared_ptr<BuildJob> Start(const Mesh& source, uint64_t stamp,
                                         const StepControl* control, StopReason* stop) {
    constexpr size_t kPart = 1 << 16;
    Mesh mesh;
    mesh.p_MV.reserve(source.p_MV.size());
    mesh.triangles.reserve(source.triangles.size());
    for (size_t at = 0; at < std::max(source.p_MV.size(), source.triangles.size()); at += kPart) {
      if (control != nullptr && (*stop = control->Check()) != StopReason::kNone) return nullptr;
      const auto copy = [at](const auto& from, auto& to) {
        if (at < from.size())
          to.insert(to.end(), from.begin() + at, from.begin() + std::min(from.size(), at + kPart));
      };
      copy(source.p_MV, mesh.p_MV);
      copy(source.triangles, mesh.triangles);
    }
    auto job = std::make_shared<BuildJob>();
    job->stamp = stamp;
    // FCL's types are made on the build's thread.
    std::thread([job, mesh = std::move(mesh)] {
      std::vector<fcl::Triangle> triangles;
      triangles.reserve(mesh.triangles.size());
      for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
      auto model = std::make_shared<Model>();
      model->beginModel();
      model->addSubModel(Points(mesh), triangles);
      model->endModel();
      std::lock_guard lock(job->mutex);
      job->model = std::move(model);
      job->finished.notify_all();
    }).detach();
    return job;
  }
  // Waits for the model, checking `control` every few milliseconds: the model, or null when the
  // control said stop (`stop` then says why).
  std::shared_ptr<Model> Wait(const StepControl* control, StopReason* stop) {
    std::unique_lock lock(mutex);
    while (
        !finished.wait_for(lock, std::chrono::milliseconds(5), [&] { return model != nullptr; })) {
      if (control == nullptr) continue;
      if ((*stop = control->Check()) != StopReason::kNone) return nullptr;
    }
    return model;
  }
};

}  // namespace

struct FclCollider::Impl {
  struct Entry {
    std::shared_ptr<Model> model;
    std::unique_ptr<fcl::CollisionObjectd> object;
    uint64_t stamp = 0;
    ObjectSlot slot{};                // the object's user data points here: entries never move
    bool registered = false;          // in `manager`
    std::shared_ptr<BuildJob> build;  // a model being built (no `model` yet)
  };
  std::vector<std::unique_ptr<Entry>> entries;  // by slot; null: no model
  fcl::DynamicAABBTreeCollisionManagerd manager;

  Entry& At(ObjectSlot slot) {
    if (Index(slot) >= entries.size()) entries.resize(Index(slot) + 1);
    if (!entries[Index(slot)]) entries[Index(slot)] = std::make_unique<Entry>();
    return *entries[Index(slot)];
  }
  // Brings the object's model up to date and to its pose; kNone, or why the control stopped
  // it while it waited for a build.
  StopReason Refresh(const Object& object, const StepControl* control);
  void SyncBroadphase(const std::vector<Object>& objects);
};

namespace {

// What the broadphase's callback gathers.
struct CollideData {
  std::vector<SlotContact> pairs;
  FclCollider::CollideStats stats;
  const StepControl* control;
};

// One broadphase pair through FCL's mesh-mesh collide; all contacts are kept. Returns true to
// stop the broadphase (the control said so, or the pairs are over its cap).
bool CollidePair(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, CollideData& data) {
  ObjectSlot slot1 = *static_cast<ObjectSlot*>(o1->getUserData());
  ObjectSlot slot2 = *static_cast<ObjectSlot*>(o2->getUserData());
  // FCL tests triangles in o1's frame, so touching pairs can flip with the order, and the
  // order the tree hands out depends on its history: the smaller slot goes first, always.
  if (slot1 > slot2) {
    std::swap(o1, o2);
    std::swap(slot1, slot2);
  }
  const auto& model1 = static_cast<const Model&>(*o1->collisionGeometry());
  const auto& model2 = static_cast<const Model&>(*o2->collisionGeometry());
  // What fcl::collide runs for two BVHModel<OBBRSS> (orientedMeshCollide in
  // collision_func_matrix-inl.h), by hand so that its count of leaf (triangle) tests can be
  // read; statistics only count.
  // At most one contact over the cap is kept: that is enough to refuse the step.
  const size_t max_contacts =
      data.control ? std::min(data.control->max_pairs, SIZE_MAX - 1) + 1 : SIZE_MAX;
  fcl::CollisionRequestd request(max_contacts, /*enable_contact=*/false);
  fcl::CollisionResultd result;
  fcl::detail::MeshCollisionTraversalNodeOBBRSS<double> node;
  fcl::detail::initialize(node, model1, o1->getTransform(), model2, o2->getTransform(), request,
                          result);
  node.enableStatistics(true);
  fcl::detail::collide(&node);
  data.stats.object_pairs++;
  data.stats.triangle_pairs_considered +=
      static_cast<size_t>(model1.num_tris) * static_cast<size_t>(model2.num_tris);
  data.stats.triangle_tests += static_cast<size_t>(node.num_leaf_tests);
  for (size_t i = 0; i < result.numContacts(); ++i) {
    const auto& contact = result.getContact(i);
    data.pairs.push_back(
        {slot1, static_cast<uint32_t>(contact.b1), slot2, static_cast<uint32_t>(contact.b2)});
  }
  if (data.control != nullptr) {
    data.stats.stopped = data.control->Check();
    if (data.stats.stopped == StopReason::kNone && data.pairs.size() > data.control->max_pairs)
      data.stats.stopped = StopReason::kPairLimit;
  }
  return data.stats.stopped != StopReason::kNone;
}

}  // namespace

// Builds a new object's model once (on a thread of its own: BuildJob), refits a deformed one,
// and moves it to its pose.
StopReason FclCollider::Impl::Refresh(const Object& object, const StepControl* control) {
  Entry& entry = At(object.slot);
  if (!entry.model) {
    const SetupScope setup(control);  // one-off: later steps move or refit it
    // A build of other vertices (a deformable object that moved since) is of no use.
    StopReason stop = StopReason::kNone;
    if (!entry.build || entry.build->stamp != object.geometry_stamp) {
      entry.build = BuildJob::Start(*object.mesh, object.geometry_stamp, control, &stop);
      if (!entry.build) return stop;
    }
    entry.model = entry.build->Wait(control, &stop);
    if (!entry.model) return stop;
    entry.build.reset();
    entry.object = std::make_unique<fcl::CollisionObjectd>(entry.model);
    entry.slot = object.slot;
    entry.stamp = object.geometry_stamp;
    entry.object->setUserData(&entry.slot);
  } else if (entry.stamp != object.geometry_stamp) {
    // FCL's end{Update,Replace}Model refit the BVH but leave the model's local box
    // (aabb_local/center/radius) as computeLocalAABB() set it, which only the
    // CollisionObject constructor calls; computeAABB() builds the broadphase box from it. So
    // the box stayed where the vertices first were, and the broadphase dropped every pair
    // the object met elsewhere. Replace, not update: update keeps the previous vertices and
    // fits every node around both frames (swept volumes for continuous collision), looser
    // for a discrete test. Top-down refit fits each node to its triangles as a build does.
    entry.model->beginReplaceModel();
    entry.model->replaceSubModel(Points(*object.mesh));
    entry.model->endReplaceModel(/*refit=*/true, /*bottomup=*/false);
    entry.model->computeLocalAABB();
    entry.stamp = object.geometry_stamp;
  }
  entry.object->setTransform(object.X_WM.linear(), object.X_WM.translation());
  entry.object->computeAABB();
  return StopReason::kNone;
}

// The broadphase tree is kept across steps, as a simulation using FCL would: objects that came
// or went are (un)registered, then update() refits it to the moved boxes.
void FclCollider::Impl::SyncBroadphase(const std::vector<Object>& objects) {
  std::unordered_set<const fcl::CollisionObjectd*> now;
  for (const Object& object : objects) now.insert(At(object.slot).object.get());
  for (auto& entry : entries) {
    if (entry && entry->registered && !now.count(entry->object.get())) {
      manager.unregisterObject(entry->object.get());
      entry->registered = false;
    }
  }
  for (const Object& object : objects) {
    Entry& entry = At(object.slot);
    if (!entry.registered) {
      manager.registerObject(entry.object.get());
      entry.registered = true;
    }
  }
  manager.update();
}

FclCollider::FclCollider() : impl_(std::make_unique<Impl>()) {}
FclCollider::~FclCollider() = default;

void FclCollider::Remove(ObjectSlot slot) {
  if (Index(slot) >= impl_->entries.size() || !impl_->entries[Index(slot)]) return;
  Impl::Entry& entry = *impl_->entries[Index(slot)];
  if (entry.registered) impl_->manager.unregisterObject(entry.object.get());
  impl_->entries[Index(slot)].reset();
}

std::vector<SlotContact> FclCollider::Collide(const std::vector<Object>& objects,
                                              CollideStats* stats, const StepControl* control) {
  // Each model built or refit is checked for: a new scene's builds take seconds.
  for (const Object& object : objects) {
    StopReason stop = impl_->Refresh(object, control);
    if (stop == StopReason::kNone && control != nullptr) stop = control->Check();
    if (stop != StopReason::kNone) {
      if (stats != nullptr) *stats = CollideStats{.stopped = stop};
      return {};
    }
  }
  impl_->SyncBroadphase(objects);
  CollideData data{{}, {}, control};
  impl_->manager.collide(&data,
                         [](fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* raw) {
                           return CollidePair(o1, o2, *static_cast<CollideData*>(raw));
                         });
  std::sort(data.pairs.begin(), data.pairs.end());
  data.pairs.erase(std::unique(data.pairs.begin(), data.pairs.end()), data.pairs.end());
  if (stats != nullptr) *stats = data.stats;
  return data.pairs;
}

}  // namespace far::internal
