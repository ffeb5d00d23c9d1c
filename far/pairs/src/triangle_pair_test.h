#pragma once

// The triangle-pair test both exact stages share (the sort-and-sweep one, exact_stage.cc, and
// the hierarchy one, bvh_stage.cc): world-frame triangle boxes, the conservative box prefilter
// and the exact predicates, with per-thread outputs merged in a deterministic order.
//
// The prefilter never rejects a pair that an exact predicate would accept:
// - contacts: two closed triangles that share a point have closed AABBs that share it too. The
//   boxes hold the corner coordinates themselves (min/max are exact) and `b.lo - a.hi > 0` is
//   exact in IEEE arithmetic (x - y == 0 only if x == y, thanks to gradual underflow).
// - distance D: triangles within distance d have boxes whose gap is <= d on every axis, and
//   TrianglesWithinDistance may accept up to D + its documented error bound, so the boxes are
//   compared with slack D + bound (DistanceSlack). Rounding to nearest is monotone, so a
//   computed gap is <= the (double) slack whenever the exact gap is.

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <vector>

#include "far/base/step_control.h"
#include "far/geometry/triangle_tests.h"
#include "far/pairs/exact_stage.h"
#include "far/pairs/world_object.h"

namespace far::internal {

/// A triangle's closed world-frame AABB.
struct TriangleBox {
  double lo[3];
  double hi[3];
  uint32_t triangle;
};

inline TrianglePoints Corners(const WorldObjectView& object, uint32_t triangle) {
  const TriangleIndices& v = object.triangles[triangle];
  return {object.p_WV[v[0]], object.p_WV[v[1]], object.p_WV[v[2]]};
}

inline TriangleBox BoxOf(const WorldObjectView& object, uint32_t triangle) {
  const TrianglePoints p = Corners(object, triangle);
  TriangleBox box;
  box.triangle = triangle;
  for (int axis = 0; axis < 3; ++axis) {
    box.lo[axis] = std::min({p.a[axis], p.b[axis], p.c[axis]});
    box.hi[axis] = std::max({p.a[axis], p.b[axis], p.c[axis]});
  }
  return box;
}

/// True iff the closed boxes are within `slack` of each other on every axis (slack 0: they
/// share a point). Exact for slack 0; never stricter than the exact gap for slack > 0.
inline bool BoxesWithin(const TriangleBox& a, const TriangleBox& b, double slack) {
  // All six comparisons, then one branch: an exit per axis mispredicts more (far-step-profile
  // --idle-ms 6, 2 threads, medians: scaling-5000 0.467 -> 0.446 and 0.484 -> 0.477 ms,
  // paper-leaves 3.36 -> 3.18 ms, breaking equal).
  bool apart = false;
  for (int axis = 0; axis < 3; ++axis) {
    apart |= (b.lo[axis] - a.hi[axis] > slack) | (a.lo[axis] - b.hi[axis] > slack);
  }
  return !apart;
}

/// The prefilter slack for a distance query whose triangles have coordinates of magnitude at
/// most `magnitude`: never smaller than the limit TrianglesWithinDistance compares with.
/// triangle_distance.cc: TrianglesWithinDistance(s, t, D) first returns false when the largest
/// axis gap of the two triangles' boxes, computed exactly as BoxesWithin computes it, exceeds
/// D + 256 eps L (eps = 2^-53, L the diagonal of the six vertices' box), and otherwise accepts
/// only pairs that pass that same box test. L <= 2 sqrt(3) magnitude, and 256 eps L is computed
/// with a few ulps of error, so 2048 eps magnitude (a factor 2.3 above) dominates it; D + that
/// rounds to a double >= D + 256 eps L rounded, because rounding to nearest is monotone. So the
/// prefilter rejects only pairs the predicate rejects.
inline double DistanceSlack(double max_distance, double magnitude) {
  constexpr double kEps = 0x1p-53;
  return max_distance + 2048 * kEps * magnitude;
}

/// What to compute for one candidate triangle pair.
struct Wanted {
  bool distance = false;  ///< distance pairs too (contacts always)
  double max_distance = 0;
  double slack = 0;                ///< the prefilter slack: 0 for contacts only, else DistanceSlack
  StepStopper* stopper = nullptr;  ///< counts the pairs found (the pair cap); may be null
};

/// One work item's output.
struct Partial {
  std::vector<SlotContact> contacts;
  std::vector<SlotDistancePair> distance_pairs;
  size_t pairs_tested = 0;
  size_t unreported = 0;  ///< pairs found and not yet added to the stopper
};

/// Adds a partial's unreported pairs to the stopper (at the end of a piece of work).
inline void Report(Partial& out, StepStopper* stopper) {
  if (stopper != nullptr) stopper->AddFound(out.unreported);
  out.unreported = 0;
}

/// An object of a pair test: its slot and its world view.
struct SlotView {
  ObjectSlot slot;
  const WorldObjectView& view;
};

/// Runs the exact tests on triangles `a` of object `object_a` and `b` of `object_b` (slots
/// object_a.slot < object_b.slot) whose boxes passed the prefilter with wanted.slack.
/// `known_apart`: the caller knows that they do not intersect (only the distance is computed).
void TestTrianglePair(const SlotView& object_a, const TriangleBox& a, const SlotView& object_b,
                      const TriangleBox& b, const Wanted& wanted, Partial& out,
                      bool known_apart = false);

/// The slots in the query's object pairs, sorted, each once. Checks that each indexes the
/// query's objects (FAR_DEMAND: a slot past them would read out of bounds) and that pairs put
/// the smaller slot first (FAR_ASSERT).
std::vector<ObjectSlot> PairedSlots(const PairQuery& query);

/// Concatenates the partial outputs and sorts them (the order does not depend on threads).
/// With a stopper, the result says why the stage stopped (an answer over the pair cap counts
/// as kPairLimit even when no thread stopped early).
ExactResult Merge(std::vector<Partial>& partials, size_t pairs_considered,
                  StepStopper* stopper = nullptr);

}  // namespace far::internal
