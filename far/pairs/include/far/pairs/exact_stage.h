#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "far/base/step_control.h"
#include "far/base/thread_pool.h"
#include "far/model/contact_pair.h"
#include "far/model/object_slot.h"
#include "far/pairs/world_object.h"

namespace far {

/// What both exact paths are asked (the sort-and-sweep exact stage, RunExactTests, and the
/// hierarchy stage, RunBvhTests): the objects by slot, the object pairs to test, and the
/// distance of a localized query.
struct PairQuery {
  /// Indexed by slot: objects[Index(s)] is the object in slot s (an empty view: a free slot).
  std::span<const WorldObjectView> objects;
  /// Slots of `objects`, object_a < object_b, each pair once.
  std::span<const SlotPair> object_pairs;
  /// Pairs within this distance are candidates (the search widens by it), and they are reported
  /// as distance pairs when want_distance_pairs. Contacts are always computed.
  std::optional<double> max_distance;
  bool want_distance_pairs = true;
  /// Cancellation, deadline and pair cap (null: none); see ExactResult::stopped.
  const StepControl* control = nullptr;
};

/// Which triangle pairs the exact stage tests: for every object pair, the listed triangles of
/// the first object against the listed triangles of the second.
struct ExactQuery : PairQuery {
  /// Optional per-slot triangle subsets, indexed like `objects` (the primitive PCS). Empty
  /// span: every triangle of every object.
  std::span<const std::vector<uint32_t>> triangle_subsets;
};

/// Exact answers by slot, sorted ascending (object_a < object_b).
struct ExactResult {
  std::vector<SlotContact> contacts;
  std::vector<SlotDistancePair> distance_pairs;
  size_t pairs_considered = 0;  ///< triangle pairs before the AABB prefilter
  size_t pairs_tested = 0;      ///< triangle pairs that reached an exact test
  /// Why the stage stopped early (its control's cancel flag, deadline or pair cap); when it is
  /// not kNone, contacts and distance_pairs are empty: a partial answer is never returned.
  StopReason stopped = StopReason::kNone;
};

/// The slots in some pair of `pairs`, sorted, each once.
std::vector<ObjectSlot> SlotsInPairs(std::span<const SlotPair> pairs);

/// Runs exact triangle-triangle tests (TrianglesIntersect, TrianglesWithinDistance) on the
/// query's candidate pairs, with a per-pair AABB prefilter, on `pool`.
/// @pre every slot in object_pairs indexes objects (checked: FAR_DEMAND); subsets hold valid
/// triangle indices.
ExactResult RunExactTests(const ExactQuery& query, ThreadPool& pool);

/// Triangle pairs named one by one, for the exact predicates: what a filter in front of them
/// (the gpu method's) could not decide.
struct TrianglePairQuery {
  /// Indexed by slot, as PairQuery::objects.
  std::span<const WorldObjectView> objects;
  /// Each with object_a < object_b, slots of `objects` (checked: FAR_DEMAND), valid triangles.
  std::span<const SlotContact> pairs;
  /// Empty, or indexed like `pairs`: 1 where the pair is known not to intersect (only its
  /// distance is computed).
  std::span<const uint8_t> known_apart;
  std::optional<double> max_distance;  ///< as PairQuery's
  bool want_distance_pairs = true;
  const StepControl* control = nullptr;
};

/// The exact tests of RunExactTests on the query's triangle pairs: a pair is a contact when its
/// closed world boxes share a point and TrianglesIntersect accepts it, and a distance pair
/// (wanted and with a limit) when TriangleDistanceIfWithin accepts it. So for any superset of
/// the pairs RunExactTests would test, the same answer. Runs on `pool`; sorted output.
ExactResult RunExactTestsOnPairs(const TrianglePairQuery& query, ThreadPool& pool);

/// The margin a cull in front of the exact tests must grow boxes by for a distance query with
/// limit `max_distance`, where every world coordinate is at most `magnitude` in absolute value:
/// TrianglesWithinDistance accepts pairs up to the limit plus its error bound (a few hundred
/// ulps of the coordinates), and a cull that grew boxes by the limit alone would drop those
/// pairs, which the exact stage and the reference report. Also covers the rounding of growing a
/// box by it (a few ulps of the coordinates and of the limit).
double CullSlack(double max_distance, double magnitude);

/// The brute-force reference: every cross-object triangle pair (AABB prefilter only), the objects
/// taken as slots 0, 1, ... in the order given. The oracle every culling path is tested against.
ExactResult BruteForceReference(std::span<const WorldObjectView> objects,
                                std::optional<double> max_distance, ThreadPool& pool,
                                const StepControl* control = nullptr);

/// The cross-object triangle pairs BruteForceReference would consider for these objects
/// (sum of n_i n_j over object pairs i < j): what a caller checks before running it.
uint64_t BruteForcePairs(std::span<const WorldObjectView> objects);

}  // namespace far
