#pragma once

// The pairs of a list of distance pairs, in the list's order: for comparing a distance query's
// pairs with a contact list.

#include <vector>

#include "far/pairs/exact_stage.h"

namespace far::testing {

inline std::vector<SlotContact> PairsOf(const std::vector<SlotDistancePair>& distance_pairs) {
  std::vector<SlotContact> pairs;
  for (const SlotDistancePair& d : distance_pairs) pairs.push_back(d.pair);
  return pairs;
}

}  // namespace far::testing
