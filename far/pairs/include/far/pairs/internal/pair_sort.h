#pragma once

// Sorting an exact stage's answer into pair order (object_a, triangle_a, object_b, triangle_b:
// slots and triangles), the order every stage reports in, whatever the number of threads.
//
// Why not std::sort: a step's merge sorts right after the pool went idle between steps, and on
// the 2-vCPU VM a comparison sort is then several times slower (most likely its branches run on a
// cold predictor: its data was just written, and no counters show it here): 620 contacts took
// 21-30 us in far-step-profile --scene scaling-5000 --idle-ms 6 (4-9 us back to back). A least
// significant digit radix sort has almost no data-dependent branches: 2-4x faster after the
// same idle gap, and as fast back to back (far_pairs_benchmark BM_SortContacts; bench/RESULTS.md,
// "bvh: the serial parts of a small step"). It sorts each pair packed into one 64-bit key
// (the four fields in the bits they use), in as few passes as the key's bits need, and sorts
// field by field only when the fields need more than 64 bits.
//
// far::internal: visible to tests, not part of the API.

#include <vector>

#include "far/model/contact_pair.h"

namespace far::internal {

/// Sorts by the pair's order (stable: equal pairs keep their order).
void SortPairs(std::vector<SlotContact>& pairs);
/// Sorts by the pair, in the same order (stable).
void SortPairs(std::vector<SlotDistancePair>& pairs);

}  // namespace far::internal
