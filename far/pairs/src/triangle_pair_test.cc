#include "triangle_pair_test.h"

#include "far/base/assert.h"
#include "far/pairs/internal/pair_sort.h"

namespace far::internal {

// The slots of the query's object pairs, each once. A slot outside the objects would read out of
// bounds: checked in every build.
std::vector<ObjectSlot> PairedSlots(const PairQuery& query) {
  for (const SlotPair& pair : query.object_pairs) {
    FAR_DEMAND(
        Index(pair.object_a) < query.objects.size() && Index(pair.object_b) < query.objects.size(),
        "an object pair of slots of the query's objects");
    FAR_ASSERT(pair.object_a < pair.object_b, "the smaller slot first");
  }
  return SlotsInPairs(query.object_pairs);
}

void TestTrianglePair(const SlotView& object_a, const TriangleBox& a, const SlotView& object_b,
                      const TriangleBox& b, const Wanted& wanted, Partial& out,
                      bool known_apart) {
  ++out.pairs_tested;
  const TrianglePoints s = Corners(object_a.view, a.triangle);
  const TrianglePoints t = Corners(object_b.view, b.triangle);
  const SlotContact pair{object_a.slot, a.triangle, object_b.slot, b.triangle};
  // Intersection needs the boxes to touch; when they do not, only the distance test can pass.
  bool intersects = false;
  const size_t before = out.contacts.size() + out.distance_pairs.size();
  if (!known_apart && (wanted.slack == 0 || BoxesWithin(a, b, 0))) {
    // The caller's prefilter found the boxes within the slack; here they also touch.
    intersects = TrianglesIntersectWithinBoxes(s, t);
    if (intersects) out.contacts.push_back(pair);
  }
  if (wanted.distance) {
    // Intersecting triangles are within any distance, at distance 0.
    if (intersects) {
      out.distance_pairs.push_back({pair, 0.0});
    } else if (auto distance = TriangleDistanceIfWithin(s, t, wanted.max_distance)) {
      out.distance_pairs.push_back({pair, *distance});
    }
  }
  // The pair cap is checked in batches: at most this many pairs per thread go uncounted.
  constexpr size_t kReportEvery = 256;
  out.unreported += out.contacts.size() + out.distance_pairs.size() - before;
  if (out.unreported >= kReportEvery) Report(out, wanted.stopper);
}

ExactResult Merge(std::vector<Partial>& partials, size_t pairs_considered, StepStopper* stopper) {
  ExactResult result;
  result.pairs_considered = pairs_considered;
  for (Partial& partial : partials) Report(partial, stopper);
  if (stopper != nullptr) {
    result.stopped = stopper->reason();
    if (result.stopped != StopReason::kNone) return result;  // a partial answer is no answer
  }
  for (Partial& partial : partials) {
    result.contacts.insert(result.contacts.end(), partial.contacts.begin(), partial.contacts.end());
    result.distance_pairs.insert(result.distance_pairs.end(), partial.distance_pairs.begin(),
                                 partial.distance_pairs.end());
    result.pairs_tested += partial.pairs_tested;
  }
  SortPairs(result.contacts);
  SortPairs(result.distance_pairs);
  return result;
}

}  // namespace far::internal
