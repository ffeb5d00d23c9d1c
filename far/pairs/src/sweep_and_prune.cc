#include "far/pairs/sweep_and_prune.h"

#include <algorithm>
#include <limits>

#include "far/base/assert.h"

// Incremental sweep-and-prune (Cohen, Lin, Manocha, Ponamgi: I-COLLIDE).
//
// Every object is an interval per axis, [min - margin/2, max + margin/2]; two objects are a pair
// when their intervals overlap (closed) on all three axes, i.e. when the gap between their boxes
// is <= margin on every axis. That is the L-infinity distance between the boxes, so every pair
// of boxes within Euclidean distance `margin` is reported (and some a little farther, up to
// sqrt(3) margin): conservative, as culling must be. Rounding cannot drop a pair: if
// lo_b - hi_a <= margin exactly then lo_b - margin/2 <= hi_a + margin/2 exactly, and rounding to
// nearest is monotone, so the computed endpoints compare the same way.
//
// Per axis the endpoints stay sorted between calls by (value, min before max); min before max on
// ties makes touching boxes overlap, and makes "A's min is before B's max" the same statement as
// "A.lo <= B.hi". The set of overlapping pairs is kept too, and repaired by the swaps: insertion
// sort swaps exactly the endpoint pairs whose order changed, once each, so when A's min moves
// before B's max the two start to overlap on that axis (they are a pair if their new boxes
// overlap on all axes) and when A's max moves before B's min they stop (they are no pair).
// New objects are found by one sweep over x that only tests pairs with a new object in them.
//
// An Update with n objects, a of them new, r removed, k pairs reported, costs
//   O(n + k)            to refresh endpoint values and drop removed objects (O(n) with r = 0),
//   O(n + s)            to repair the order and the pairs by insertion sort, s = endpoint swaps
//                       (last_swaps()), ~0 under temporal coherence,
//   O(a log a + n + k_a) to merge the new objects' endpoints and find their pairs (k_a: pairs of
//                       a new object with any object that overlap on x),
//   O(k log k)          to sort the reported pairs.
// If s passes kSwapBudgetPerEndpoint per endpoint (the scene jumped), the axes are re-sorted in
// O(n log n) and the pairs found by a full sweep over x, O(n + k_x) with k_x pairs overlapping on
// x, as a fresh SAP would. Memory is O(n + k).

namespace far {
namespace {

constexpr size_t kSwapBudgetPerEndpoint = 16;
constexpr uint32_t kNotActive = std::numeric_limits<uint32_t>::max();

// The sort order of endpoints: by value, and on equal values every min before every max.
bool EndpointLess(double a_value, bool a_is_max, double b_value, bool b_is_max) {
  return a_value < b_value || (a_value == b_value && !a_is_max && b_is_max);
}

}  // namespace

bool SweepAndPrune::Overlap(uint32_t a, uint32_t b) const {
  const Slot& x = slots_[a];
  const Slot& y = slots_[b];
  if (x.empty || y.empty) return false;
  for (int axis = 0; axis < 3; ++axis) {
    if (x.lo[axis] > y.hi[axis] || y.lo[axis] > x.hi[axis]) return false;
  }
  return true;
}

uint64_t SweepAndPrune::PairKey(uint32_t a, uint32_t b) {
  return static_cast<uint64_t>(std::min(a, b)) << 32 | std::max(a, b);
}

bool SweepAndPrune::EndpointOrder(const Endpoint& a, const Endpoint& b) {
  return EndpointLess(a.value, a.is_max, b.value, b.is_max);
}

// Refreshes every object's grown interval. An object whose box was empty has no pairs and its
// endpoints sit at +inf in an order that says nothing about overlap, so one that turns non-empty
// is looked at afresh, like a new one.
SweepAndPrune::Refreshed SweepAndPrune::RefreshSlots(std::span<const SlotBox> boxes,
                                                     double margin) {
  const double inf = std::numeric_limits<double>::infinity();
  Refreshed refreshed;
  for (const SlotBox& slot_box : boxes) {
    const auto s = static_cast<uint32_t>(Index(slot_box.slot));
    if (s >= slots_.size()) slots_.resize(s + 1);
    Slot& slot = slots_[s];
    FAR_ASSERT(slot.stamp != stamp_, "slots must be unique");
    const bool added = !slot.live;
    if (added) refreshed.added.push_back(s);
    const bool was_empty = !added && slot.empty;
    slot.live = true;
    slot.stamp = stamp_;
    // An empty or non-finite box pairs with nothing; its endpoints park at +inf so that they
    // keep the lists totally ordered (a NaN would break the sort for everyone).
    const Eigen::AlignedBox3d grown = GrownBox(slot_box.box_W, margin);
    slot.empty = grown.isEmpty();
    refreshed.any_empty = refreshed.any_empty || slot.empty;
    if (was_empty && !slot.empty) refreshed.revived.push_back(s);
    for (int axis = 0; axis < 3; ++axis) {
      slot.lo[axis] = slot.empty ? inf : grown.min()[axis];
      slot.hi[axis] = slot.empty ? inf : grown.max()[axis];
    }
  }
  return refreshed;
}

Eigen::AlignedBox3d SweepAndPrune::GrownBox(const Eigen::AlignedBox3d& box_W, double margin) {
  const Eigen::Vector3d& lo = box_W.min();
  const Eigen::Vector3d& hi = box_W.max();
  if (!(lo.allFinite() && hi.allFinite() && (lo.array() <= hi.array()).all()))
    return Eigen::AlignedBox3d();  // empty
  // A negative or NaN margin is treated as 0 (Update's contract asks for margin >= 0).
  const double half = margin > 0 ? margin / 2 : 0.0;
  return Eigen::AlignedBox3d(lo.array() - half, hi.array() + half);
}

// Forgets the objects that were not in this Update, with their endpoints and pairs.
void SweepAndPrune::DropUnseen() {
  bool any_removed = false;
  for (Slot& slot : slots_) {
    if (!slot.live || slot.stamp == stamp_) continue;
    slot.live = false;
    any_removed = true;
  }
  if (!any_removed) return;
  const auto dead = [this](const Endpoint& e) { return !slots_[e.slot].live; };
  for (auto& axis : axes_) std::erase_if(axis, dead);
  std::erase_if(overlaps_, [this](uint64_t pair) {
    return !slots_[pair >> 32].live || !slots_[static_cast<uint32_t>(pair)].live;
  });
}

// Moves axis `a`'s endpoints to their new values and repairs the order by insertion sort, and
// the pairs with it: each swap of a min and a max is two objects starting or ceasing to overlap
// on this axis. Returns true when the axis was too far from sorted and was sorted afresh (its
// pairs then say nothing). Then merges in the endpoints of the new objects.
bool SweepAndPrune::RepairAxis(int a, bool rebuild, std::span<const uint32_t> added) {
  std::vector<Endpoint>& axis = axes_[a];
  for (Endpoint& e : axis) e.value = e.is_max ? slots_[e.slot].hi[a] : slots_[e.slot].lo[a];
  const size_t budget = kSwapBudgetPerEndpoint * axis.size() + 64;
  size_t swaps = 0;
  for (size_t i = 1; i < axis.size() && swaps <= budget; ++i) {
    const Endpoint moving = axis[i];
    size_t j = i;
    for (; j > 0 && EndpointOrder(moving, axis[j - 1]); --j) {
      const Endpoint& passed = axis[j - 1];
      if (!rebuild && moving.is_max != passed.is_max && moving.slot != passed.slot) {
        if (moving.is_max) {
          overlaps_.erase(PairKey(moving.slot, passed.slot));  // now apart on this axis
        } else if (Overlap(moving.slot, passed.slot)) {
          overlaps_.insert(PairKey(moving.slot, passed.slot));  // now together on this axis
        }
      }
      axis[j] = passed;
    }
    axis[j] = moving;
    swaps += i - j;
  }
  // Too far from sorted (objects jumped): a full sort is cheaper than finishing.
  const bool resorted = swaps > budget;
  if (resorted) std::sort(axis.begin(), axis.end(), EndpointOrder);
  last_swaps_ += swaps;
  if (!added.empty()) {
    const auto old_size = static_cast<std::ptrdiff_t>(axis.size());
    for (uint32_t s : added) {
      axis.push_back({slots_[s].lo[a], s, false});
      axis.push_back({slots_[s].hi[a], s, true});
    }
    std::sort(axis.begin() + old_size, axis.end(), EndpointOrder);
    std::inplace_merge(axis.begin(), axis.begin() + old_size, axis.end(), EndpointOrder);
  }
  return resorted;
}

// Finds the pairs of the objects marked in `is_new` by sweeping x: an object is active from its
// min to its max, and on entry meets the active objects it overlaps on x; an old object only
// needs to meet the new ones.
void SweepAndPrune::SweepNewPairs(const std::vector<uint8_t>& is_new) {
  std::vector<uint32_t> active[2];  // [0] old, [1] new
  std::vector<uint32_t> active_index(slots_.size(), kNotActive);
  for (const Endpoint& e : axes_[0]) {
    std::vector<uint32_t>& own = active[is_new[e.slot]];
    if (e.is_max) {
      // Swap-remove from the active set (an empty box was never added).
      const uint32_t index = active_index[e.slot];
      if (index == kNotActive) continue;
      own[index] = own.back();
      active_index[own[index]] = index;
      own.pop_back();
      active_index[e.slot] = kNotActive;
      continue;
    }
    if (slots_[e.slot].empty) continue;
    for (int list = is_new[e.slot] ? 0 : 1; list < 2; ++list) {
      for (uint32_t other : active[list]) {
        if (Overlap(e.slot, other)) overlaps_.insert(PairKey(e.slot, other));
      }
    }
    active_index[e.slot] = static_cast<uint32_t>(own.size());
    own.push_back(e.slot);
  }
}

std::vector<SlotPair> SweepAndPrune::Update(std::span<const SlotBox> boxes, double margin) {
  FAR_ASSERT(margin >= 0, "a distance");
  ++stamp_;
  last_swaps_ = 0;
  const Refreshed refreshed = RefreshSlots(boxes, margin);
  DropUnseen();
  bool rebuild = false;  // an axis was re-sorted: find all pairs afresh
  for (int a = 0; a < 3; ++a) rebuild = RepairAxis(a, rebuild, refreshed.added) || rebuild;
  if (rebuild) overlaps_.clear();
  if (rebuild || !refreshed.added.empty() || !refreshed.revived.empty()) {
    std::vector<uint8_t> is_new(slots_.size(), rebuild ? 1 : 0);
    for (uint32_t s : refreshed.added) is_new[s] = 1;
    for (uint32_t s : refreshed.revived) is_new[s] = 1;
    SweepNewPairs(is_new);
  }
  // An object whose box turned empty loses its pairs (two that both turn empty keep their tied
  // order at +inf, so no swap would tell).
  if (refreshed.any_empty) {
    std::erase_if(overlaps_, [this](uint64_t pair) {
      return slots_[pair >> 32].empty || slots_[static_cast<uint32_t>(pair)].empty;
    });
  }
  // Report the pairs, sorted (PairKey puts the smaller slot in the high half).
  std::vector<SlotPair> pairs;
  pairs.reserve(overlaps_.size());
  for (uint64_t pair : overlaps_) {
    pairs.push_back({SlotAt(pair >> 32), SlotAt(static_cast<uint32_t>(pair))});
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace far
