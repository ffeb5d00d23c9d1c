#pragma once

// Sorting an exact stage's answer into ContactPair order (object_a, triangle_a, object_b,
// triangle_b), the order every stage reports in, whatever the number of threads.
//
// Why not std::sort: a step's merge sorts right after the pool went idle between steps, and on
// the 2-vCPU VM a comparison sort then pays for a cold branch predictor: 620 contacts took
// 21-30 us in far-step-profile --scene scaling-5000 --idle-ms 6 (4 us back to back). A least
// significant digit radix sort has almost no data-dependent branches: 2.5-3.5x faster after
// the same idle gap (bench/RESULTS.md, "Sorting a step's contacts").

#include <vector>

#include "far/model/contact_pair.h"

namespace far::internal {

/// Sorts by ContactPair's order (stable: equal pairs keep their order).
void SortPairs(std::vector<ContactPair>& pairs);
/// Sorts by the pair, in the same order (stable).
void SortPairs(std::vector<DistancePair>& pairs);

}  // namespace far::internal
