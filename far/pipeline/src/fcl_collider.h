#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Geometry>

#include "far/base/step_control.h"
#include "far/model/contact_pair.h"
#include "far/model/mesh.h"
#include "far/model/object_slot.h"

namespace far::internal {

/// FCL as a comparison method: a BVHModel<OBBRSS> per object (built once, refit when a
/// deformable object's vertices change), a dynamic AABB tree broadphase kept across calls, and
/// FCL's mesh-mesh collide reporting every intersecting triangle pair: the answer FCL gives on
/// fresh models of the same objects. Objects are kept by slot (far/model/object_slot.h). FCL
/// types stay in the .cc. A new object's model is built on a thread of its own, which a call
/// stopped by its control leaves running: FCL's build cannot be interrupted (seconds for a
/// large object), and the next call takes the model it made.
class FclCollider {
 public:
  struct Object {
    ObjectSlot slot;
    uint64_t geometry_stamp;  ///< changes when the vertices change: triggers a refit
    const Mesh* mesh;         ///< frame M; aliased for the call
    Eigen::Isometry3d X_WM;
  };

  /// What one Collide call did.
  struct CollideStats {
    size_t object_pairs = 0;               ///< object pairs FCL's broadphase passed to collide
    size_t triangle_pairs_considered = 0;  ///< sum over those pairs of n_a * n_b triangles
    size_t triangle_tests = 0;  ///< triangle pairs whose leaf boxes overlapped: FCL's tests
    /// Why it stopped early (checked after each object's model is brought up to date, every
    /// few milliseconds while a new model is built, and between object pairs: FCL's collide
    /// of one pair runs to its end); the contacts are then incomplete and must not be reported.
    StopReason stopped = StopReason::kNone;
  };

  FclCollider();
  ~FclCollider();

  /// Returns FCL's contact pairs by slot (sorted, object_a < object_b) among `objects`; `stats`
  /// (may be null) gets what it took.
  std::vector<SlotContact> Collide(const std::vector<Object>& objects, CollideStats* stats,
                                   const StepControl* control = nullptr);
  /// Forgets the model of the object in `slot`.
  void Remove(ObjectSlot slot);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace far::internal
