#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Geometry>

#include "far/contact_pair.h"

namespace far {

/// An object's id and its world-frame axis-aligned bounding box.
struct IdBox {
  uint32_t id = 0;
  Eigen::AlignedBox3d box_W;
};

/// Object-level sweep-and-prune (I-COLLIDE style), incremental across steps: the sorted
/// endpoint lists are kept between calls and repaired by insertion sort, so objects that did not
/// move cost no re-sorting. Thread safety: none (one owner).
class SweepAndPrune {
 public:
  /// Replaces the set of boxes (any order, ids unique; ids absent from `boxes` are removed)
  /// and returns every pair whose boxes are within `margin` of each other (boxes closed:
  /// touching counts), sorted ascending with object_a < object_b. @pre margin >= 0.
  std::vector<ObjectPair> Update(std::span<const IdBox> boxes, double margin = 0.0);

  /// Number of endpoint swaps the last Update performed (0 when nothing moved).
  size_t last_swaps() const { return last_swaps_; }

 private:
  struct Endpoint {
    double value;
    uint32_t slot;
    bool is_max;
  };
  std::vector<Endpoint> axes_[3];
  std::vector<uint32_t> slot_ids_;
  size_t last_swaps_ = 0;
};

}  // namespace far
