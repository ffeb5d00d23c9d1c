#include "fcl_collider.h"

#include <algorithm>
#include <unordered_set>

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/narrowphase/collision.h>

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
  };
  std::unordered_map<uint32_t, Entry> entries;
  fcl::DynamicAABBTreeCollisionManagerd manager;
};

FclCollider::FclCollider() : impl_(std::make_unique<Impl>()) {}
FclCollider::~FclCollider() = default;

void FclCollider::Remove(uint32_t id) {
  auto it = impl_->entries.find(id);
  if (it == impl_->entries.end()) return;
  impl_->manager.unregisterObject(it->second.object.get());
  impl_->entries.erase(it);
}

std::vector<ContactPair> FclCollider::Collide(const std::vector<Object>& objects,
                                              size_t* narrow_pairs) {
  // Build new models once; refit deformed ones; move every object to its pose.
  std::vector<fcl::CollisionObjectd*> registered;
  for (const Object& object : objects) {
    Impl::Entry& entry = impl_->entries[object.id];
    if (!entry.model) {
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
      entry.model->beginUpdateModel();
      entry.model->updateSubModel(Points(*object.mesh));
      entry.model->endUpdateModel(/*refit=*/true, /*bottomup=*/true);
      entry.object->computeAABB();
      entry.stamp = object.geometry_stamp;
    }
    entry.object->setTransform(object.X_WM.linear(), object.X_WM.translation());
    entry.object->computeAABB();
    registered.push_back(entry.object.get());
  }
  // The broadphase tree is kept across steps, as a simulation using FCL would: objects that
  // came or went are (un)registered, then update() refits it to the moved boxes.
  std::unordered_set<fcl::CollisionObjectd*> now(registered.begin(), registered.end());
  std::vector<fcl::CollisionObjectd*> known;
  impl_->manager.getObjects(known);
  for (fcl::CollisionObjectd* object : known) {
    if (!now.count(object)) impl_->manager.unregisterObject(object);
  }
  const std::unordered_set<fcl::CollisionObjectd*> had(known.begin(), known.end());
  for (fcl::CollisionObjectd* object : registered) {
    if (!had.count(object)) impl_->manager.registerObject(object);
  }
  impl_->manager.update();
  auto& manager = impl_->manager;

  // Every broadphase pair goes through FCL's mesh-mesh collide; all contacts are kept.
  struct Data {
    std::vector<ContactPair> pairs;
    size_t narrow = 0;
  } data;
  manager.collide(&data, [](fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* raw) {
    auto* data = static_cast<Data*>(raw);
    fcl::CollisionRequestd request(/*num_max_contacts=*/std::numeric_limits<size_t>::max(),
                                   /*enable_contact=*/false);
    fcl::CollisionResultd result;
    fcl::collide(o1, o2, request, result);
    data->narrow++;
    uint32_t id1 = *static_cast<uint32_t*>(o1->getUserData());
    uint32_t id2 = *static_cast<uint32_t*>(o2->getUserData());
    for (size_t i = 0; i < result.numContacts(); ++i) {
      const auto& contact = result.getContact(i);
      ContactPair pair{id1, static_cast<uint32_t>(contact.b1), id2,
                       static_cast<uint32_t>(contact.b2)};
      if (id1 > id2) pair = {id2, pair.triangle_b, id1, pair.triangle_a};
      data->pairs.push_back(pair);
    }
    return false;  // keep going
  });
  std::sort(data.pairs.begin(), data.pairs.end());
  data.pairs.erase(std::unique(data.pairs.begin(), data.pairs.end()), data.pairs.end());
  if (narrow_pairs != nullptr) *narrow_pairs = data.narrow;
  return data.pairs;
}

}  // namespace far::internal
