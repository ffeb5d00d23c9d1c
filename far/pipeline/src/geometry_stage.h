#pragma once

#include <span>

#include "far/base/thread_pool.h"
#include "far/model/step_result.h"
#include "far/pairs/world_object.h"

namespace far::internal {

/// Objects' closedness (IsClosedMesh), decided once per object and kept until its slot is
/// freed: the geometry stage asks only for objects in contact. Thread safety: none.
class ClosednessCache {
 public:
  /// Whether the mesh in slot `slot_index` (its triangles `triangles` over `num_vertices`
  /// vertices) is closed; computed on first use.
  bool IsClosed(size_t slot_index, std::span<const TriangleIndices> triangles, size_t num_vertices);
  /// Forgets a freed slot (its id and slot may come back with another mesh).
  void Forget(size_t slot_index);

 private:
  std::vector<int8_t> closed_;  // by slot: -1 unknown, 0 open, 1 closed
};

/// The geometry stage (StepRequest::geometry): fills result.contact_geometry for
/// result.contacts, result.closest_points for result.distance_pairs and result.penetrations
/// for the object pairs with contacts, from the world views by slot. `id_of_slot` maps slots
/// to the ids the result speaks. Runs its pair loops on `pool`.
void ComputeGeometry(std::span<const WorldObjectView> views, std::span<const uint32_t> id_of_slot,
                     ThreadPool& pool, ClosednessCache& closedness, StepResult& result);

}  // namespace far::internal
