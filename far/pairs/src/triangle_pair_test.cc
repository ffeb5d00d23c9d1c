#include "triangle_pair_test.h"

namespace far::internal {

void TestTrianglePair(const WorldObjectView& object_a, const TriangleBox& a,
                      const WorldObjectView& object_b, const TriangleBox& b, const Wanted& wanted,
                      Partial& out) {
  ++out.pairs_tested;
  const TrianglePoints s = Corners(object_a, a.triangle);
  const TrianglePoints t = Corners(object_b, b.triangle);
  const ContactPair pair{object_a.id, a.triangle, object_b.id, b.triangle};
  // Intersection needs the boxes to touch; when they do not, only the distance test can pass.
  bool intersects = false;
  if (wanted.contacts && (wanted.slack == 0 || BoxesWithin(a, b, 0))) {
    intersects = TrianglesIntersect(s, t);
    if (intersects) out.contacts.push_back(pair);
  }
  if (wanted.distance) {
    // Intersecting triangles are within any distance, at distance 0.
    if (intersects) {
      out.distance_pairs.push_back({pair, 0.0});
    } else if (TrianglesWithinDistance(s, t, wanted.max_distance)) {
      out.distance_pairs.push_back({pair, TriangleDistance(s, t)});
    }
  }
}

ExactResult Merge(std::vector<Partial>& partials, size_t pairs_considered) {
  ExactResult result;
  result.pairs_considered = pairs_considered;
  for (Partial& partial : partials) {
    result.contacts.insert(result.contacts.end(), partial.contacts.begin(), partial.contacts.end());
    result.distance_pairs.insert(result.distance_pairs.end(), partial.distance_pairs.begin(),
                                 partial.distance_pairs.end());
    result.pairs_tested += partial.pairs_tested;
  }
  std::sort(result.contacts.begin(), result.contacts.end());
  std::sort(result.distance_pairs.begin(), result.distance_pairs.end());
  return result;
}

}  // namespace far::internal
