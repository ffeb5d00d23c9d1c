#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "far/base/step_control.h"
#include "far/model/mesh.h"

namespace far {

/// A bounding volume hierarchy of one mesh's triangles in the mesh's own frame M: axis-aligned
/// boxes, built by binned surface-area heuristic down to leaves of at most kLeafSize triangles
/// (every range that small is a leaf: fewer node pairs for a descent to visit). A rigid
/// or static object builds it once; a deformable one refits it when its vertices move (and
/// rebuilds it when refitting has made it much looser). Boxes hold the vertex coordinates
/// themselves (min/max in double, exact), so every triangle lies in the closed box of each of
/// its ancestors. A built tree also keeps two slabs per triangle (slabs(): its plane, and across
/// it): a descent uses them as separating axes, which for thin and slanted triangles cut far
/// more than the boxes do.
/// Thread safety: none (one owner); const methods may run concurrently.
class TriangleBvh {
 public:
  static constexpr int kLeafSize = 8;
  // A descent keeps a leaf's live triangles as bits of a 32-bit word, one bit kept for a flag.
  static_assert(kLeafSize < 32);

  /// One node: a box as center and half extents, and a leaf when count > 0 (triangles
  /// order()[first, first + count)), else an inner node with children first and first + 1.
  /// Every vertex p of the node's triangles satisfies |p - center| <= half_extent on each axis
  /// in exact arithmetic (the half extents are rounded up).
  struct Node {
    Eigen::Vector3d center;
    Eigen::Vector3d half_extent;
    uint32_t first = 0;
    uint32_t count = 0;
    bool leaf() const { return count > 0; }
  };

  /// A triangle's two best separating axes, each with the triangle's extent along it: its
  /// normal (a slab of zero thickness: its plane) and the direction across it in its plane,
  /// perpendicular to its longest edge (for a sliver, a slab as thin as the sliver). Stored in
  /// float, 40 bytes instead of 80 (the largest part of a hierarchy, read at every leaf a descent
  /// reaches): each axis is the unit axis scaled by 1 - 2^-22 and rounded, so its length is
  /// just under 1 (an axis no longer than 1 shows no gap larger than the distance), or zero where
  /// the triangle has no plane (degenerate) or no longest edge to cross, and then never
  /// separates anything. Any nonzero axis is a valid separating axis; only its bounds must be
  /// right: [lo[k], hi[k]] holds axis[k] . (p - c) for the triangle's three vertices p, with c the
  /// center of the triangle's leaf (Node::center), each projection computed in double (within a
  /// few ulps of |p| + |c| of the exact one; a caller's margin must cover that, and the descent's
  /// 2^-40 of the coordinates' magnitude does, by a factor of over a thousand) and the bounds
  /// rounded outward to float. Relative to the leaf, the float bounds lose nothing that matters
  /// far from the origin: their rounding is a few float steps of the leaf's size (2^-23 each), not
  /// of its position. A third axis, along the longest edge, was measured and cut nothing more
  /// (far_bvh_benchmark BM_Pair_BvhFans): the boxes already bound that direction.
  struct Slab {
    static constexpr int kAxes = 2;
    Eigen::Vector3f axis[kAxes];  ///< the normal; across the triangle (normal x longest edge)
    float lo[kAxes] = {0, 0}, hi[kAxes] = {0, 0};  ///< along axis[k], relative to the leaf
    /// axis[k] in double (exactly).
    Eigen::Vector3d Axis(int k) const { return axis[k].cast<double>(); }
  };

  /// Builds the hierarchy of `triangles` over `p_MV` (@pre indices in range, finite). With a
  /// stopper, polls it every few tens of thousands of triangles sorted into nodes (a build of
  /// a million triangles takes a second or more): when it says stop, the build is abandoned,
  /// the hierarchy left empty, and false returned.
  bool Build(std::span<const Eigen::Vector3d> p_MV, std::span<const TriangleIndices> triangles,
             StepStopper* stopper = nullptr);

  /// Recomputes every box for new vertex positions (same triangles) in O(n), keeping the tree;
  /// rebuilds instead when the refit tree's boxes have grown to kRebuildGrowth times the surface
  /// area they had when it was built. Returns true when it rebuilt. A refit tree keeps no slabs
  /// (slabs() is empty until the next Build): a deformable object refits every step, and its
  /// slabs would cost as much again as the refit (far_bvh_benchmark BM_Hierarchy_Refit: 0.33 ms
  /// without, 0.70 ms with the plane alone, 20K triangles) for the one step they would serve.
  /// A rebuild polls `stopper` as Build does (stopped: the hierarchy is left empty).
  bool Refit(std::span<const Eigen::Vector3d> p_MV, std::span<const TriangleIndices> triangles,
             StepStopper* stopper = nullptr);

  const std::vector<Node>& nodes() const { return nodes_; }
  /// Triangle indices in leaf order.
  const std::vector<uint32_t>& order() const { return order_; }
  /// Per triangle in leaf order (slabs()[k] belongs to triangle order()[k]), in frame M and
  /// relative to the center of the leaf that holds k; empty after a Refit that did not rebuild.
  const std::vector<Slab>& slabs() const { return slabs_; }
  bool empty() const { return nodes_.empty(); }

  /// Refit trees whose summed node surface area grows past this factor are rebuilt.
  static constexpr double kRebuildGrowth = 2.0;

 private:
  struct Builder;

  std::vector<Node> nodes_;  // nodes_[0] is the root
  std::vector<uint32_t> order_;
  std::vector<Slab> slabs_;
  double built_area_ = 0;  // summed node surface area right after Build
};

}  // namespace far
