#include "fcl_collider.h"

#include <algorithm>
#include <limits>
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

}  // namespace

struct FclCollider::Impl {
  struct Entry {
    std::shared_ptr<Model> model;
    std::unique_ptr<fcl::CollisionObjectd> object;
    uint64_t stamp = 0;
    uint32_t id = 0;
    bool registered = false;  // in `manager`
  };
  std::unordered_map<uint32_t, Entry> entries;
  fcl::DynamicAABBTreeCollisionManagerd manager;
};

FclCollider::FclCollider() : impl_(std::make_unique<Impl>()) {}
FclCollider::~FclCollider() = default;

void FclCollider::Remove(uint32_t id) {
  auto it = impl_->entries.find(id);
  if (it == impl_->entries.end()) return;
  if (it->second.registered) impl_->manager.unregisterObject(it->second.object.get());
  impl_->entries.erase(it);
}

std::vector<ContactPair> FclCollider::Collide(const std::vector<Object>& objects,
                                              CollideStats* stats, const StepControl* control) {
  // Build new models once; refit deformed ones; move every object to its pose.
  std::vector<fcl::CollisionObjectd*> present;
  for (const Object& object : objects) {
    Impl::Entry& entry = impl_->entries[object.id];
    if (!entry.model) {
      const SetupScope setup(control);  // one-off: later steps move or refit it
      entry.model = std::make_shared<Model>();
      entry.model->beginModel();
      std::vector<fcl::Triangle> triangles;
      for (const auto& t : object.mesh->triangles) triangles.emplace_back(t[0], t[1], t[2]);
      entry.model->addSubModel(Points(*object.mesh), triangles);
      entry.model->endModel();
      entry.object = std::make_unique<fcl::CollisionObjectd>(entry.model);
      entry.id = object.id;
      entry.stamp = object.geometry_stamp;
      entry.object->setUserData(&entry.id);
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
    present.push_back(entry.object.get());
  }
  // The broadphase tree is kept across steps, as a simulation using FCL would: objects that
  // came or went are (un)registered, then update() refits it to the moved boxes.
  std::unordered_set<fcl::CollisionObjectd*> now(present.begin(), present.end());
  for (auto& [id, entry] : impl_->entries) {
    if (entry.registered && !now.count(entry.object.get())) {
      impl_->manager.unregisterObject(entry.object.get());
      entry.registered = false;
    }
  }
  for (const Object& object : objects) {
    Impl::Entry& entry = impl_->entries.at(object.id);
    if (!entry.registered) {
      impl_->manager.registerObject(entry.object.get());
      entry.registered = true;
    }
  }
  impl_->manager.update();

  // Every broadphase pair goes through FCL's mesh-mesh collide; all contacts are kept.
  struct Data {
    std::vector<ContactPair> pairs;
    CollideStats stats;
    const StepControl* control;
  } data{{}, {}, control};
  impl_->manager.collide(&data, [](fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2,
                                   void* raw) {
    auto* data = static_cast<Data*>(raw);
    uint32_t id1 = *static_cast<uint32_t*>(o1->getUserData());
    uint32_t id2 = *static_cast<uint32_t*>(o2->getUserData());
    // FCL tests triangles in o1's frame, so touching pairs can flip with the order, and the
    // order the tree hands out depends on its history: the smaller id goes first, always.
    if (id1 > id2) {
      std::swap(o1, o2);
      std::swap(id1, id2);
    }
    const auto& model1 = static_cast<const Model&>(*o1->collisionGeometry());
    const auto& model2 = static_cast<const Model&>(*o2->collisionGeometry());
    // What fcl::collide runs for two BVHModel<OBBRSS> (orientedMeshCollide in
    // collision_func_matrix-inl.h), by hand so that its count of leaf (triangle) tests can be
    // read; statistics only count.
    // At most one contact over the cap is kept: that is enough to refuse the step.
    const size_t max_contacts =
        data->control ? std::min(data->control->max_pairs, SIZE_MAX - 1) + 1 : SIZE_MAX;
    fcl::CollisionRequestd request(max_contacts, /*enable_contact=*/false);
    fcl::CollisionResultd result;
    fcl::detail::MeshCollisionTraversalNodeOBBRSS<double> node;
    fcl::detail::initialize(node, model1, o1->getTransform(), model2, o2->getTransform(), request,
                            result);
    node.enableStatistics(true);
    fcl::detail::collide(&node);
    data->stats.object_pairs++;
    data->stats.triangle_pairs_considered +=
        static_cast<size_t>(model1.num_tris) * static_cast<size_t>(model2.num_tris);
    data->stats.triangle_tests += static_cast<size_t>(node.num_leaf_tests);
    for (size_t i = 0; i < result.numContacts(); ++i) {
      const auto& contact = result.getContact(i);
      data->pairs.push_back(
          {id1, static_cast<uint32_t>(contact.b1), id2, static_cast<uint32_t>(contact.b2)});
    }
    if (data->control != nullptr) {
      data->stats.stopped = data->control->Check();
      if (data->stats.stopped == StopReason::kNone && data->pairs.size() > data->control->max_pairs)
        data->stats.stopped = StopReason::kPairLimit;
    }
    return data->stats.stopped != StopReason::kNone;  // true: stop the broadphase
  });
  std::sort(data.pairs.begin(), data.pairs.end());
  data.pairs.erase(std::unique(data.pairs.begin(), data.pairs.end()), data.pairs.end());
  if (stats != nullptr) *stats = data.stats;
  return data.pairs;
}

}  // namespace far::internal
