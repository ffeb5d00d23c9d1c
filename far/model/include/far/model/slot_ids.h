#pragma once

// Where ids come back: a step's answers, found by slot, turned into the ids the user named the
// objects by (object_slot.h), sorted as a StepResult promises.

#include <algorithm>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "far/model/contact_pair.h"
#include "far/model/object_slot.h"

namespace far {

/// The ids of a step's objects by slot: `id_of_slot[Index(slot)]`. Aliased: the span must
/// outlive *this.
class SlotIds {
 public:
  explicit SlotIds(std::span<const uint32_t> id_of_slot) : id_of_slot_(id_of_slot) {}

  uint32_t operator()(ObjectSlot slot) const { return id_of_slot_[Index(slot)]; }

  /// The pair by ids, its two sides swapped when that puts the smaller id first.
  ObjectPair WithIds(const SlotPair& pair) const {
    const uint32_t a = (*this)(pair.object_a), b = (*this)(pair.object_b);
    return a < b ? ObjectPair{a, b} : ObjectPair{b, a};
  }
  ContactPair WithIds(const SlotContact& pair) const {
    const uint32_t a = (*this)(pair.object_a), b = (*this)(pair.object_b);
    return a < b ? ContactPair{a, pair.triangle_a, b, pair.triangle_b}
                 : ContactPair{b, pair.triangle_b, a, pair.triangle_a};
  }
  DistancePair WithIds(const SlotDistancePair& pair) const {
    return {WithIds(pair.pair), pair.distance};
  }

  /// Every pair by ids, sorted. Sorting costs nothing more than a check when the slots' order is
  /// the ids' (objects added in id order, the usual case).
  template <typename SlotPairType>
  auto WithIds(std::span<const SlotPairType> pairs) const {
    std::vector<decltype(WithIds(pairs.front()))> with_ids;
    with_ids.reserve(pairs.size());
    for (const SlotPairType& pair : pairs) with_ids.push_back(WithIds(pair));
    if (!std::is_sorted(with_ids.begin(), with_ids.end()))
      std::sort(with_ids.begin(), with_ids.end());
    return with_ids;
  }
  template <typename SlotPairType>
  auto WithIds(const std::vector<SlotPairType>& pairs) const {
    return WithIds(std::span<const SlotPairType>(pairs));
  }

 private:
  std::span<const uint32_t> id_of_slot_;
};

}  // namespace far
