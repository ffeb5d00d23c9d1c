#pragma once

#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>

#include "far/model/contact_pair.h"
#include "far/model/mesh.h"

namespace far::internal {

/// FCL as a comparison method: a BVHModel<OBBRSS> per object (built once, refit when a
/// deformable object's vertices change), a dynamic AABB tree broadphase, and FCL's
/// mesh-mesh collide reporting every intersecting triangle pair. FCL types stay in the .cc.
class FclCollider {
 public:
  struct Object {
    uint32_t id;
    uint64_t geometry_stamp;  ///< changes when the vertices change: triggers a refit
    const Mesh* mesh;         ///< frame M; aliased for the call
    Eigen::Isometry3d X_WM;
  };

  FclCollider();
  ~FclCollider();

  /// Returns FCL's contact pairs (sorted, object_a < object_b) among `objects`.
  /// `narrow_pairs` gets the number of object pairs FCL's broadphase passed to collide.
  std::vector<ContactPair> Collide(const std::vector<Object>& objects, size_t* narrow_pairs);
  /// Forgets an object's model.
  void Remove(uint32_t id);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace far::internal
