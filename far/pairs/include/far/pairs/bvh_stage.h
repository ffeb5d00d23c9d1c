#pragma once

#include <optional>
#include <span>
#include <vector>

#include <Eigen/Geometry>

#include "far/base/thread_pool.h"
#include "far/model/contact_pair.h"
#include "far/model/step_result.h"
#include "far/pairs/exact_stage.h"
#include "far/pairs/triangle_bvh.h"
#include "far/pairs/world_object.h"

namespace far {

/// An object's hierarchy in its own frame M and the pose X_WM that places M in the world. Its
/// world view (PairQuery::objects) must be X_WM applied to the vertices the hierarchy was built
/// or refit from, then FlushTinyCoordinates (as the pipeline computes them).
struct ObjectHierarchy {
  const TriangleBvh* bvh = nullptr;  ///< aliased; null or empty: the object pairs with nothing
  Eigen::Isometry3d X_WM = Eigen::Isometry3d::Identity();
};

/// What the hierarchy stage is asked: the object pairs (PairQuery) and each object's hierarchy.
struct BvhQuery : PairQuery {
  /// Indexed like `objects` (by slot).
  std::span<const ObjectHierarchy> hierarchies;
  bool run_exact = true;        ///< false: no exact tests (only candidates, when asked)
  bool want_candidates = true;  ///< fill BvhResult::candidates (the primitive PCS)
};

/// The answer, and the candidate triangles: per slot (indexed like `objects`), sorted, the
/// triangles whose world box is within the query's slack of a triangle box of a partner, where
/// no slab of either triangle (its plane or the direction across it, see RunBvhTests) separates
/// the two.
struct BvhResult {
  ExactResult exact;
  std::vector<std::vector<uint32_t>> candidates;
  DescentCounters counters;  ///< what the descent did (the same for any number of threads)
};

/// The hierarchy stage: for every object pair, a simultaneous descent of the two hierarchies in
/// the frame of each (the relative pose composed in double; boxes compared along the six face
/// axes of both, with a margin that covers the query distance and every rounding of the world
/// vertices and of the test itself). Once it reaches a leaf, the leaf descends the other
/// hierarchy alone, and each of its triangles' slabs (TriangleBvh::slabs: the triangle's plane,
/// and across it) are further separating axes with the same margin: a triangle apart from a node is
/// dropped for that node's subtree, and at the other hierarchy's leaves that leaf's slabs drop its
/// triangles apart from the first leaf's box. Of the triangle pairs left, those whose world
/// boxes meet (the exact stage's prefilter) are tested once more along both triangles' slabs,
/// turned into the world, against the other triangle's world corners; the pairs no slab
/// separates go to the exact predicates of the exact stage (RunExactTests). Never drops a pair the
/// exact predicates would accept: the answer equals BruteForceReference's for the same pairs.
/// Runs on `pool`; the output does not depend on the number of threads.
BvhResult RunBvhTests(const BvhQuery& query, ThreadPool& pool);

}  // namespace far
