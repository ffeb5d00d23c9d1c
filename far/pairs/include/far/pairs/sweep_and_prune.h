#pragma once

#include <cstdint>
#include <span>
#include <unordered_set>
#include <vector>

#include <Eigen/Geometry>

#include "far/model/contact_pair.h"
#include "far/model/object_slot.h"

namespace far {

/// An object's slot and its world-frame axis-aligned bounding box.
struct SlotBox {
  ObjectSlot slot{};
  Eigen::AlignedBox3d box_W;
};

/// Object-level sweep-and-prune (I-COLLIDE style), incremental across steps: the sorted
/// endpoint lists are kept between calls and repaired by insertion sort, so objects that did not
/// move cost no re-sorting. Objects are tracked by slot (far/model/object_slot.h): its arrays are
/// indexed by slot, so memory grows with the largest slot seen. Thread safety: none (one owner).
class SweepAndPrune {
 public:
  /// Replaces the set of boxes (any order, slots unique; slots absent from `boxes` are removed)
  /// and returns every pair whose boxes are within `margin` of each other (boxes closed:
  /// touching counts), sorted ascending with object_a < object_b. A slot whose object changed
  /// since the last call (removed, and the slot given to a new one) is tracked as one object
  /// that moved: the answer is the same. @pre margin >= 0.
  std::vector<SlotPair> Update(std::span<const SlotBox> boxes, double margin = 0.0);

  /// The box Update tests for `box_W` at `margin`: each side moved out by margin / 2, rounded
  /// as Update rounds it; two objects are a pair when theirs overlap, closed, on every axis.
  /// An empty or non-finite box gives an empty one: it pairs with nothing.
  static Eigen::AlignedBox3d GrownBox(const Eigen::AlignedBox3d& box_W, double margin);

  /// Number of endpoint swaps the last Update performed (0 when nothing moved).
  size_t last_swaps() const { return last_swaps_; }

 private:
  // One endpoint of one object's grown interval on one axis.
  struct Endpoint {
    double value;
    uint32_t slot;
    bool is_max;
  };
  // A tracked object (by slot): its grown box and when it was last seen.
  struct Slot {
    bool live = false;
    bool empty = false;  // empty or non-finite input box: pairs with nothing
    uint64_t stamp = 0;  // the Update that last saw it
    double lo[3] = {0, 0, 0};
    double hi[3] = {0, 0, 0};
  };
  // What RefreshSlots found.
  struct Refreshed {
    std::vector<uint32_t> added;    // slots not live before
    std::vector<uint32_t> revived;  // slots whose box turned non-empty
    bool any_empty = false;
  };
  Refreshed RefreshSlots(std::span<const SlotBox> boxes, double margin);
  void DropUnseen();
  bool RepairAxis(int axis, bool rebuild, std::span<const uint32_t> added);
  void SweepNewPairs(const std::vector<uint8_t>& is_new);
  bool Overlap(uint32_t a, uint32_t b) const;  // grown boxes overlap on every axis
  static uint64_t PairKey(uint32_t a, uint32_t b);
  static bool EndpointOrder(const Endpoint& a, const Endpoint& b);

  std::vector<Endpoint> axes_[3];          // sorted by (value, min before max)
  std::vector<Slot> slots_;                // indexed by slot
  std::unordered_set<uint64_t> overlaps_;  // slot pairs (low << 32 | high) overlapping on all axes
  uint64_t stamp_ = 0;
  size_t last_swaps_ = 0;
};

}  // namespace far
