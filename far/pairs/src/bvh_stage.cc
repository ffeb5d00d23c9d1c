#include "far/pairs/bvh_stage.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "triangle_pair_test.h"

#include "far/base/assert.h"

// Why the descent never drops a pair the exact predicates accept. The exact stage tests the
// world vertices p_WV = flush(fl(X_WM p_MV)) (WorldVertex, far/model/world_vertex.h). A node's
// box holds its triangles' p_MV exactly, so the exactly transformed triangles lie in the node's
// box moved by X_WM (an oriented box). Each world vertex is within delta <= 8 eps (sqrt(3) |p_M|
// + |t|) + 2^-255 of its exact image (eps = 2^-53: three products and sums per coordinate; the
// flush moves a point by less than 2^-255 along any unit axis). Two rounded triangles the
// predicates accept are within D + err (TrianglesWithinDistance's bound, inside DistanceSlack),
// so their exact images are within D + err + 2 delta, and so are the two oriented boxes: no
// separating axis can show a larger gap. The test below compares the gap along the face axes of
// both boxes with margin = slack + 2^-40 (the boxes' and poses' magnitudes) + 2^-246, which also
// covers the rounding of the relative pose and of the test itself (tens of eps of the same
// magnitudes, far below 2^-40 = 8192 eps) and the flush of both triangles (2^-254). The same
// holds for a triangle's slabs as axes: the triangle's exact vertices project into [lo, hi]
// (relative to its leaf's center c, bounds rounded outward to float) up to a few ulps of |p| +
// |c|, and an axis no longer than 1 shows no gap larger than the distance. At two leaves a slab
// turned into the world (axis R_WM n, bounds shifted by that axis . X_WM c) is compared with the
// other triangle's world corners, the very points the predicates test: the rounding of the
// pose's product, a few eps of the same magnitudes, is inside the margin too.

namespace far {
namespace {

using internal::BoxesWithin;
using internal::BoxOf;
using internal::Partial;
using internal::SlotView;
using internal::TestTrianglePair;
using internal::TriangleBox;
using internal::Wanted;
using Node = TriangleBvh::Node;

// The relative pose of a pair, prepared once: B's boxes into A's frame and A's into B's.
struct PairFrame {
  uint32_t a = 0, b = 0;  // slots (Index) of the query's objects, a the smaller
  Eigen::Matrix3d R_AB, abs_R_AB, R_BA, abs_R_BA;
  Eigen::Vector3d t_AB, t_BA;
  double margin = 0;
  // Both frames have the same rotation (static, deformable and unrotated objects): B's boxes
  // are A's boxes translated, and the test along A's axes is the whole test.
  bool aligned = false;
  // Whether A's and B's poses rotate (a triangle's slabs then turn into the world with them).
  bool rotated_a = false, rotated_b = false;
};

// max |coordinate| of a node box.
double BoxMagnitude(const Node& node) {
  return (node.center.cwiseAbs() + node.half_extent).maxCoeff();
}

PairFrame MakePairFrame(const ObjectHierarchy& a, const ObjectHierarchy& b, uint32_t ia,
                        uint32_t ib, double slack) {
  PairFrame f;
  f.a = ia;
  f.b = ib;
  const Eigen::Matrix3d R_AW = a.X_WM.linear().transpose();
  f.R_AB = R_AW * b.X_WM.linear();
  f.t_AB = R_AW * (b.X_WM.translation() - a.X_WM.translation());
  f.R_BA = f.R_AB.transpose();
  f.t_BA = -(f.R_BA * f.t_AB);
  f.abs_R_AB = f.R_AB.cwiseAbs();
  f.abs_R_BA = f.R_BA.cwiseAbs();
  f.aligned = a.X_WM.linear() == b.X_WM.linear();
  f.rotated_a = a.X_WM.linear() != Eigen::Matrix3d::Identity();
  f.rotated_b = b.X_WM.linear() != Eigen::Matrix3d::Identity();
  const double scale = 2 * (BoxMagnitude(a.bvh->nodes()[0]) + BoxMagnitude(b.bvh->nodes()[0])) +
                       a.X_WM.translation().cwiseAbs().maxCoeff() +
                       b.X_WM.translation().cwiseAbs().maxCoeff();
  f.margin = slack + 0x1p-40 * scale + 0x1p10 * kTinyWorldCoordinate;  // the last: 2^-246
  return f;
}

// A pair of nodes still to descend, each node's box also moved into the other's frame (so that
// descending one node reuses the other's).
struct Task {
  uint32_t frame;
  uint32_t x, y;               // node of A, node of B
  Eigen::Vector3d cy_A, ey_A;  // y's box in A's frame (center, half extents)
  Eigen::Vector3d cx_B, ex_B;  // x's box in B's frame
};

void MoveIntoA(const PairFrame& f, const Node& y, Task& t) {
  if (f.aligned) {
    t.cy_A = y.center + f.t_AB;
    t.ey_A = y.half_extent;
  } else {
    t.cy_A = f.R_AB * y.center + f.t_AB;
    t.ey_A = f.abs_R_AB * y.half_extent;
  }
}
void MoveIntoB(const PairFrame& f, const Node& x, Task& t) {
  if (f.aligned) return;  // not needed: OverlapInB passes
  t.cx_B = f.R_BA * x.center + f.t_BA;
  t.ex_B = f.abs_R_BA * x.half_extent;
}

// The gap tests of a task's two boxes: no gap larger than the margin along A's three axes (with
// y moved into A) ...
bool OverlapInA(const PairFrame& f, const Node& x, const Task& t) {
  const Eigen::Array3d gap = (x.center - t.cy_A).array().abs() - (x.half_extent + t.ey_A).array();
  return !(gap > f.margin).any();
}
// ... nor along B's three (with x moved into B). Together: a conservative overlap test.
bool OverlapInB(const PairFrame& f, const Node& y, const Task& t) {
  if (f.aligned) return true;  // the same axes as A's
  const Eigen::Array3d gap = (y.center - t.cx_B).array().abs() - (y.half_extent + t.ex_B).array();
  return !(gap > f.margin).any();
}

double NodeSize(const Node& n) { return n.half_extent.sum(); }

// One chunk's output: the exact answers and the descent's counters; and the stack DescendLeaf
// reuses.
struct Output {
  Partial partial;
  size_t considered = 0;
  DescentCounters counters;
  std::vector<std::pair<uint32_t, uint32_t>> leaf_stack;
};

// Everything a descent reads, and the candidate marks every thread writes: per object, per
// triangle, 1 when it met a partner's triangle (relaxed atomic stores of the same value).
struct Descent {
  const BvhQuery& query;
  const std::vector<PairFrame>& frames;

  const ObjectHierarchy& hierarchy(uint32_t o) const { return query.hierarchies[o]; }
  SlotView view(uint32_t o) const { return {SlotAt(o), query.objects[o]}; }
  const Wanted& wanted;
  std::vector<std::vector<uint8_t>>& marks;  // empty when candidates are not asked for

  void Mark(uint32_t object, uint32_t triangle) const {
    std::atomic_ref<uint8_t>(marks[object][triangle]).store(1, std::memory_order_relaxed);
  }
};

// A leaf of one object (L) prepared for a descent of the other object's hierarchy (T): its
// box and its triangles' slabs, moved into T's frame. A node of T is passed over when its box is
// apart from the leaf's along T's axes, or when every triangle of the leaf is apart from it
// along one of its slabs' axes: the node's box, projected onto the axis (the triangle's normal,
// or across it), lies beyond the triangle's own projection. For the thin, slanted triangles
// that make axis-aligned boxes loose (slivers, fans, tilted leaves) those are the separating
// axes the boxes lack. Margins as for the boxes: the projections below are dot products of the
// same magnitudes, a few ulps each, and an approximate unit axis is still a valid axis (a gap
// along it is at most the distance, up to a few ulps).
struct LeafProbe {
  const Node* leaf = nullptr;
  bool leaf_in_a = true;                  // L is the pair's A (T is B), or the other way round
  const Eigen::Matrix3d* R_LT = nullptr;  // null: aligned (the same rotation)
  const Eigen::Matrix3d* abs_R_LT = nullptr;
  Eigen::Vector3d t_LT;
  Eigen::Vector3d center, half_extent;  // the leaf's box in T (an AABB around its OBB)
  uint32_t count = 0;
  bool has_slabs = false;
  static constexpr int kAxes = TriangleBvh::Slab::kAxes;
  Eigen::Vector3d axis[TriangleBvh::kLeafSize][kAxes];                          // in T
  double lo[TriangleBvh::kLeafSize][kAxes], hi[TriangleBvh::kLeafSize][kAxes];  // along them, in T
};

LeafProbe MakeProbe(const PairFrame& f, const TriangleBvh& leaf_bvh, const Node& leaf,
                    bool leaf_in_a) {
  FAR_DEMAND(leaf.count <= TriangleBvh::kLeafSize, "Build makes no larger leaf");
  LeafProbe p;
  p.leaf = &leaf;
  p.leaf_in_a = leaf_in_a;
  p.count = leaf.count;
  // p_L = R_LT p_T + t_LT and p_T = R_TL p_L + t_TL.
  const Eigen::Matrix3d& R_TL = leaf_in_a ? f.R_BA : f.R_AB;
  const Eigen::Matrix3d& abs_R_TL = leaf_in_a ? f.abs_R_BA : f.abs_R_AB;
  const Eigen::Vector3d& t_TL = leaf_in_a ? f.t_BA : f.t_AB;
  const Eigen::Vector3d& t_LT = leaf_in_a ? f.t_AB : f.t_BA;
  if (!f.aligned) {
    p.R_LT = leaf_in_a ? &f.R_AB : &f.R_BA;
    p.abs_R_LT = leaf_in_a ? &f.abs_R_AB : &f.abs_R_BA;
  }
  p.t_LT = t_LT;
  p.center =
      f.aligned ? Eigen::Vector3d(leaf.center + t_TL) : Eigen::Vector3d(R_TL * leaf.center + t_TL);
  p.half_extent = f.aligned ? leaf.half_extent : Eigen::Vector3d(abs_R_TL * leaf.half_extent);
  p.has_slabs = !leaf_bvh.slabs().empty();
  // n . (p_L - c) = (R_TL n) . p_T - n . (c - t_LT), c the leaf's center.
  const Eigen::Vector3d offset = leaf.center - t_LT;
  for (uint32_t i = 0; i < leaf.count && p.has_slabs; ++i) {
    const TriangleBvh::Slab& slab = leaf_bvh.slabs()[leaf.first + i];
    for (int k = 0; k < LeafProbe::kAxes; ++k) {
      const Eigen::Vector3d axis = slab.Axis(k);
      const double shift = axis.dot(offset);
      p.axis[i][k] = f.aligned ? axis : Eigen::Vector3d(R_TL * axis);
      p.lo[i][k] = slab.lo[k] + shift;
      p.hi[i][k] = slab.hi[k] + shift;
    }
  }
  return p;
}

// The probe's triangles, among `live` (bit i: triangle i), whose slabs do not separate `node`.
uint32_t LiveAgainst(const LeafProbe& p, const Node& node, uint32_t live, double margin) {
  if (!p.has_slabs) return live;
  // Every triangle (live or not) and every axis, then one mask: exits that skip the rest
  // mispredict, the more so in a step after an idle gap, whose predictor has forgotten what it
  // learned (bench/RESULTS.md, "bvh: branches after an idle gap").
  uint32_t kept = 0;
  for (uint32_t i = 0; i < p.count; ++i) {
    bool apart = false;
    for (int k = 0; k < LeafProbe::kAxes; ++k) {
      const double middle = p.axis[i][k].dot(node.center);
      const double radius = p.axis[i][k].cwiseAbs().dot(node.half_extent);
      apart |= (middle - radius > p.hi[i][k] + margin) | (middle + radius < p.lo[i][k] - margin);
    }
    kept |= static_cast<uint32_t>(!apart) << i;
  }
  return kept & live;
}

// The triangles of a leaf of T whose slabs do not separate the probe's leaf (its oriented box:
// center in T, axes R_TL, the leaf's own half extents).
uint32_t TreeLeafLive(const LeafProbe& p, const TriangleBvh& tree, const Node& leaf,
                      double margin) {
  if (tree.slabs().empty()) return (1u << leaf.count) - 1;
  const Eigen::Vector3d center = p.center - leaf.center;  // the slabs are relative to the leaf
  uint32_t kept = 0;
  for (uint32_t j = 0; j < leaf.count; ++j) {
    const TriangleBvh::Slab& slab = tree.slabs()[leaf.first + j];
    bool apart = false;
    for (int k = 0; k < TriangleBvh::Slab::kAxes && !apart; ++k) {
      const Eigen::Vector3d axis = slab.Axis(k);
      const double middle = axis.dot(center);
      // |R_TL^T n| . e_L: the OBB's extent along the axis.
      const Eigen::Vector3d n_L = p.R_LT != nullptr ? Eigen::Vector3d(*p.R_LT * axis) : axis;
      const double radius = n_L.cwiseAbs().dot(p.leaf->half_extent);
      apart = middle - radius > slab.hi[k] + margin || middle + radius < slab.lo[k] - margin;
    }
    if (!apart) kept |= 1u << j;
  }
  return kept;
}

// A triangle's slabs (TriangleBvh::Slab) moved into the world frame, made when first needed.
struct WorldSlab {
  bool made = false;
  bool valid = false;  // false: the object keeps no slabs (refit), nothing is separated
  Eigen::Vector3d axis[TriangleBvh::Slab::kAxes];
  double lo[TriangleBvh::Slab::kAxes], hi[TriangleBvh::Slab::kAxes];
};

// `leaf_center_W`: the center of the triangle's leaf in the world, X_WM c.
void MakeWorldSlab(const ObjectHierarchy& object, bool rotated, uint32_t leaf_index,
                   const Eigen::Vector3d& leaf_center_W, WorldSlab& w) {
  w.made = true;
  if (object.bvh->slabs().empty()) return;
  const TriangleBvh::Slab& slab = object.bvh->slabs()[leaf_index];
  w.valid = true;
  for (int k = 0; k < TriangleBvh::Slab::kAxes; ++k) {
    w.axis[k] = rotated ? Eigen::Vector3d(object.X_WM.linear() * slab.Axis(k)) : slab.Axis(k);
    const double shift = w.axis[k].dot(leaf_center_W);
    w.lo[k] = slab.lo[k] + shift;
    w.hi[k] = slab.hi[k] + shift;
  }
}

// Whether one of s's slabs has all of the triangle's world corners beyond it (by more than the
// margin).
bool SlabSeparates(const WorldSlab& s, const WorldObjectView& object, uint32_t triangle,
                   double margin) {
  if (!s.valid) return false;
  const TriangleIndices& v = object.triangles[triangle];
  const Eigen::Vector3d& a = object.p_WV[v[0]];
  const Eigen::Vector3d& b = object.p_WV[v[1]];
  const Eigen::Vector3d& c = object.p_WV[v[2]];
  // Every axis, then one answer: an exit per axis mispredicts (as in BoxesWithin).
  bool apart = false;
  for (int k = 0; k < TriangleBvh::Slab::kAxes; ++k) {
    const double da = s.axis[k].dot(a), db = s.axis[k].dot(b), dc = s.axis[k].dot(c);
    const double least = std::min({da, db, dc}), most = std::max({da, db, dc});
    apart |= (least > s.hi[k] + margin) | (most < s.lo[k] - margin);
  }
  return apart;
}

// The live triangle pairs of two leaves (x of A, y of B): world boxes, then each triangle's
// slabs against the other's world corners, then the exact tests. The slabs turned into the
// world are made once per triangle and call, and only for triangles whose box met a partner's:
// computing the axes anew from the world corners cut as many tests and saved no time
// (docs/culling.md).
void TestLeaves(const Descent& d, const PairFrame& f, const Node& x, uint32_t live_x, const Node& y,
                uint32_t live_y, Output& out) {
  const ObjectHierarchy& a = d.hierarchy(f.a);
  const ObjectHierarchy& b = d.hierarchy(f.b);
  const SlotView view_a = d.view(f.a), view_b = d.view(f.b);
  TriangleBox boxes_a[TriangleBvh::kLeafSize], boxes_b[TriangleBvh::kLeafSize];
  uint32_t index_a[TriangleBvh::kLeafSize], index_b[TriangleBvh::kLeafSize];
  WorldSlab slabs_a[TriangleBvh::kLeafSize], slabs_b[TriangleBvh::kLeafSize];
  uint32_t na = 0, nb = 0;
  for (uint32_t i = 0; i < x.count; ++i) {
    if (live_x >> i & 1) {
      index_a[na] = x.first + i;
      boxes_a[na++] = BoxOf(view_a.view, a.bvh->order()[x.first + i]);
    }
  }
  for (uint32_t j = 0; j < y.count; ++j) {
    if (live_y >> j & 1) {
      index_b[nb] = y.first + j;
      boxes_b[nb++] = BoxOf(view_b.view, b.bvh->order()[y.first + j]);
    }
  }
  out.considered += size_t{na} * nb;
  ++out.counters.leaf_pairs;
  const Eigen::Vector3d x_W = a.X_WM * x.center, y_W = b.X_WM * y.center;
  for (uint32_t i = 0; i < na; ++i) {
    // The pairs whose boxes meet, as a mask computed without a branch per pair (one there
    // mispredicts often: 40% of the pairs meet on breaking); the loop visits only those.
    uint32_t met = 0;
    for (uint32_t j = 0; j < nb; ++j) {
      met |= static_cast<uint32_t>(BoxesWithin(boxes_a[i], boxes_b[j], d.wanted.slack)) << j;
    }
    // Counted bit by bit below: std::popcount is a library call on baseline x86-64 (no popcnt).
    for (; met != 0; met &= met - 1) {
      ++out.counters.boxes_met;
      const uint32_t j = static_cast<uint32_t>(std::countr_zero(met));
      if (!slabs_a[i].made) MakeWorldSlab(a, f.rotated_a, index_a[i], x_W, slabs_a[i]);
      if (SlabSeparates(slabs_a[i], view_b.view, boxes_b[j].triangle, f.margin)) continue;
      if (!slabs_b[j].made) MakeWorldSlab(b, f.rotated_b, index_b[j], y_W, slabs_b[j]);
      if (SlabSeparates(slabs_b[j], view_a.view, boxes_a[i].triangle, f.margin)) continue;
      if (!d.marks.empty()) {
        d.Mark(f.a, boxes_a[i].triangle);
        d.Mark(f.b, boxes_b[j].triangle);
      }
      if (d.query.run_exact) {
        TestTrianglePair(view_a, boxes_a[i], view_b, boxes_b[j], d.wanted, out.partial);
      }
    }
  }
}

// Descends T's hierarchy from `root` against the probe's leaf, keeping per node the leaf's
// triangles that its slabs have not yet separated (a triangle apart from a node is apart from
// everything below it), down to T's leaves.
void DescendLeaf(const Descent& d, const PairFrame& f, const LeafProbe& p, uint32_t root,
                 Output& out) {
  const ObjectHierarchy& tree_object = d.hierarchy(p.leaf_in_a ? f.b : f.a);
  const TriangleBvh& tree = *tree_object.bvh;
  const auto& nodes = tree.nodes();
  // Stack entries: a node of T and the probe's triangles still live above it (bit i: triangle i),
  // with kBoxesTested set for the root, whose box the caller has already found overlapping.
  constexpr uint32_t kBoxesTested = 1u << 31;
  const uint32_t all = (1u << p.count) - 1;
  std::vector<std::pair<uint32_t, uint32_t>>& stack = out.leaf_stack;
  stack.assign(1, {root, all | kBoxesTested});
  ++out.counters.leaf_descents;
  for (uint32_t visited = 0; !stack.empty(); ++visited) {
    if (visited % 256 == 255 && d.wanted.stopper->Poll()) return;
    const auto [index, entry] = stack.back();
    stack.pop_back();
    const Node& node = nodes[index];
    ++out.counters.leaf_descent_nodes;
    const uint32_t parent_live = entry & ~kBoxesTested;
    if (!(entry & kBoxesTested)) {
      const Eigen::Array3d gap =
          (node.center - p.center).array().abs() - (node.half_extent + p.half_extent).array();
      if ((gap > f.margin).any()) continue;
      if (p.R_LT != nullptr) {  // and along L's axes, the node moved into L
        const Eigen::Array3d gap_L =
            ((*p.R_LT * node.center + p.t_LT) - p.leaf->center).array().abs() -
            (*p.abs_R_LT * node.half_extent + p.leaf->half_extent).array();
        if ((gap_L > f.margin).any()) continue;
      }
    }
    const uint32_t live = LiveAgainst(p, node, parent_live, f.margin);
    if (live == 0) continue;
    if (!node.leaf()) {
      stack.emplace_back(node.first, live);
      stack.emplace_back(node.first + 1, live);
      continue;
    }
    const uint32_t tree_live = TreeLeafLive(p, tree, node, f.margin);
    if (tree_live == 0) continue;
    if (p.leaf_in_a) {
      TestLeaves(d, f, *p.leaf, live, node, tree_live, out);
    } else {
      TestLeaves(d, f, node, tree_live, *p.leaf, live, out);
    }
  }
}

// A node pair where at least one node is a leaf: the leaf (x when both are) probes the other.
void DescendFromLeaf(const Descent& d, const PairFrame& f, uint32_t x, uint32_t y, Output& out) {
  const TriangleBvh& bvh_a = *d.hierarchy(f.a).bvh;
  const TriangleBvh& bvh_b = *d.hierarchy(f.b).bvh;
  const Node& node_x = bvh_a.nodes()[x];
  if (node_x.leaf()) {
    DescendLeaf(d, f, MakeProbe(f, bvh_a, node_x, /*leaf_in_a=*/true), y, out);
  } else {
    DescendLeaf(d, f, MakeProbe(f, bvh_b, bvh_b.nodes()[y], /*leaf_in_a=*/false), x, out);
  }
}

// Descends an overlapping task of two inner nodes one level: the children pairs of its bigger
// node that overlap too are pushed onto `next`, except that, with `out`, a pair with a leaf is
// descended from its leaf at once (seeding passes no `out`: it leaves the work to the pool).
void Expand(const Descent& d, const Task& task, std::vector<Task>& next, Output* out,
            DescentCounters& counters) {
  ++counters.node_pairs;
  const PairFrame& f = d.frames[task.frame];
  const auto& nodes_a = d.hierarchy(f.a).bvh->nodes();
  const auto& nodes_b = d.hierarchy(f.b).bvh->nodes();
  const Node& x = nodes_a[task.x];
  const Node& y = nodes_b[task.y];
  const bool split_x = NodeSize(x) >= NodeSize(y);
  for (uint32_t child : {split_x ? x.first : y.first, (split_x ? x.first : y.first) + 1}) {
    // The kept node's box is already in the other frame: test that side first, and move the
    // child only when it passes.
    Task t = task;
    if (split_x) {
      t.x = child;
      if (!OverlapInA(f, nodes_a[child], t)) continue;
      MoveIntoB(f, nodes_a[child], t);
      if (!OverlapInB(f, y, t)) continue;
    } else {
      t.y = child;
      if (!OverlapInB(f, nodes_b[child], t)) continue;
      MoveIntoA(f, nodes_b[child], t);
      if (!OverlapInA(f, x, t)) continue;
    }
    if (out != nullptr && (nodes_a[t.x].leaf() || nodes_b[t.y].leaf())) {
      DescendFromLeaf(d, f, t.x, t.y, *out);
    } else {
      next.push_back(t);
    }
  }
}

// Whether a task has reached a leaf on either side (then it is descended from that leaf).
bool HasLeaf(const Descent& d, const Task& task) {
  const PairFrame& f = d.frames[task.frame];
  return d.hierarchy(f.a).bvh->nodes()[task.x].leaf() ||
         d.hierarchy(f.b).bvh->nodes()[task.y].leaf();
}

// The descent of an aligned pair (same rotation: boxes differ by a translation only), with
// small tasks: the plain box test along the shared axes.
void DescendAligned(const Descent& d, const PairFrame& f, uint32_t root_x, uint32_t root_y,
                    Output& out) {
  const auto& nodes_a = d.hierarchy(f.a).bvh->nodes();
  const auto& nodes_b = d.hierarchy(f.b).bvh->nodes();
  const auto overlap = [&](const Node& x, const Node& y) {
    const Eigen::Array3d gap =
        (x.center - y.center - f.t_AB).array().abs() - (x.half_extent + y.half_extent).array();
    return !(gap > f.margin).any();
  };
  std::vector<std::pair<uint32_t, uint32_t>> stack = {{root_x, root_y}};
  for (uint32_t visited = 0; !stack.empty(); ++visited) {
    if (visited % 256 == 255 && d.wanted.stopper->Poll()) return;
    const auto [ix, iy] = stack.back();
    stack.pop_back();
    const Node& x = nodes_a[ix];
    const Node& y = nodes_b[iy];
    if (x.leaf() || y.leaf()) {
      DescendFromLeaf(d, f, ix, iy, out);
      continue;
    }
    ++out.counters.node_pairs;
    const bool split_x = NodeSize(x) >= NodeSize(y);
    const uint32_t first = split_x ? x.first : y.first;
    for (uint32_t child : {first, first + 1}) {
      const uint32_t cx = split_x ? child : ix, cy = split_x ? iy : child;
      if (overlap(nodes_a[cx], nodes_b[cy])) stack.emplace_back(cx, cy);
    }
  }
}

// Depth-first descent of one overlapping task to its leaves.
void Descend(const Descent& d, const Task& root, Output& out) {
  const PairFrame& f = d.frames[root.frame];
  if (f.aligned) return DescendAligned(d, f, root.x, root.y, out);
  std::vector<Task> stack = {root};
  for (uint32_t visited = 0; !stack.empty(); ++visited) {
    if (visited % 256 == 255 && d.wanted.stopper->Poll()) return;
    const Task task = stack.back();
    stack.pop_back();
    if (HasLeaf(d, task)) {
      DescendFromLeaf(d, f, task.x, task.y, out);
    } else {
      Expand(d, task, stack, &out, out.counters);
    }
  }
}

// The object pairs whose objects both have a hierarchy, as frames.
std::vector<PairFrame> MakeFrames(const BvhQuery& query, double slack) {
  std::vector<PairFrame> frames;
  for (const SlotPair& pair : query.object_pairs) {
    const auto a = static_cast<uint32_t>(Index(pair.object_a));
    const auto b = static_cast<uint32_t>(Index(pair.object_b));
    const ObjectHierarchy& oa = query.hierarchies[a];
    const ObjectHierarchy& ob = query.hierarchies[b];
    if (oa.bvh == nullptr || ob.bvh == nullptr || oa.bvh->empty() || ob.bvh->empty()) continue;
    frames.push_back(MakePairFrame(oa, ob, a, b, slack));
  }
  return frames;
}

// The overlapping root pairs, expanded breadth-first until there are enough tasks to share among
// threads.
std::vector<Task> SeedTasks(const Descent& d, size_t target, DescentCounters& counters) {
  std::vector<Task> tasks;
  for (uint32_t i = 0; i < d.frames.size(); ++i) {
    const PairFrame& f = d.frames[i];
    const Node& x = d.hierarchy(f.a).bvh->nodes()[0];
    const Node& y = d.hierarchy(f.b).bvh->nodes()[0];
    Task root{i, 0, 0, {}, {}, {}, {}};
    MoveIntoA(f, y, root);
    MoveIntoB(f, x, root);
    if (OverlapInA(f, x, root) && OverlapInB(f, y, root)) tasks.push_back(root);
  }
  while (!tasks.empty() && tasks.size() < target) {
    std::vector<Task> next;
    for (const Task& task : tasks) {
      if (HasLeaf(d, task)) {
        next.push_back(task);  // descended from its leaf later, on the pool
      } else {
        Expand(d, task, next, nullptr, counters);
      }
    }
    const bool growing = next.size() > tasks.size();
    tasks = std::move(next);
    if (!growing) break;  // mostly leaves left: descend what there is
  }
  return tasks;
}

// Appends the indices of the nonzero marks in order. Few triangles of a large object are
// candidates: the scan skips eight unmarked ones at a time.
void CollectMarked(const std::vector<uint8_t>& marks, std::vector<uint32_t>& marked) {
  const size_t n = marks.size();
  size_t t = 0;
  for (; t + 8 <= n; t += 8) {
    uint64_t word;
    std::memcpy(&word, marks.data() + t, sizeof word);
    if (word == 0) continue;
    for (size_t k = t; k < t + 8; ++k) {
      if (marks[k]) marked.push_back(static_cast<uint32_t>(k));
    }
  }
  for (; t < n; ++t) {
    if (marks[t]) marked.push_back(static_cast<uint32_t>(t));
  }
}

// The largest |coordinate| of the world vertices of the paired objects (for DistanceSlack).
double WorldMagnitude(const BvhQuery& query, std::span<const ObjectSlot> paired) {
  double magnitude = 0;
  for (ObjectSlot o : paired) {
    for (const Eigen::Vector3d& p : query.objects[Index(o)].p_WV)
      magnitude = std::max(magnitude, p.cwiseAbs().maxCoeff());
  }
  return magnitude;
}

}  // namespace

BvhResult RunBvhTests(const BvhQuery& query, ThreadPool& pool) {
  // The distance widens the search (candidates within it) even when no distance pair is asked.
  FAR_DEMAND(query.hierarchies.size() == query.objects.size(), "hierarchies indexed by slot");
  const std::vector<ObjectSlot> paired = internal::PairedSlots(query);
  StepStopper stopper(query.control);
  Wanted wanted;
  wanted.stopper = &stopper;
  const bool within = query.max_distance.has_value() && *query.max_distance >= 0;
  wanted.distance = within && query.want_distance_pairs;
  if (within) {
    wanted.max_distance = *query.max_distance;
    wanted.slack = internal::DistanceSlack(wanted.max_distance, WorldMagnitude(query, paired));
  }
  const std::vector<PairFrame> frames = MakeFrames(query, wanted.slack);
  std::vector<std::vector<uint8_t>> marks;
  if (query.want_candidates) {
    marks.resize(query.objects.size());
    for (const PairFrame& f : frames) {
      marks[f.a].resize(query.objects[f.a].triangles.size(), 0);
      marks[f.b].resize(query.objects[f.b].triangles.size(), 0);
    }
  }
  const Descent descent{query, frames, wanted, marks};

  // Seed tasks on this thread, then descend them on the pool. About 16 tasks per thread: the
  // workers wait while this thread seeds, and each level seeded breadth-first is a level not
  // descended depth-first in cache (far-step-profile --idle-ms 6 on 2 threads, against 64 per
  // thread: scaling-5000 7-11% and breaking 1-15% faster; 4 per thread was slower on breaking).
  constexpr size_t kTasksPerThread = 16;
  const size_t threads = static_cast<size_t>(pool.num_threads());
  DescentCounters seeding;
  const std::vector<Task> tasks = SeedTasks(descent, kTasksPerThread * threads, seeding);
  const size_t grain = std::clamp<size_t>(tasks.size() / (16 * threads), 1, 256);
  std::vector<Output> outputs((tasks.size() + grain - 1) / grain);
  pool.ParallelFor(tasks.size(), grain, [&](size_t begin, size_t end) {
    Output& out = outputs[begin / grain];
    for (size_t i = begin; i < end && !stopper.Poll(); ++i) Descend(descent, tasks[i], out);
  });

  // Merge: sorted answers and candidates, whatever the number of threads.
  BvhResult result;
  result.counters = seeding;
  std::vector<Partial> partials;
  size_t considered = 0;
  for (Output& out : outputs) {
    considered += out.considered;
    result.counters += out.counters;
    partials.push_back(std::move(out.partial));
  }
  result.candidates.resize(marks.size());
  for (size_t o = 0; o < marks.size(); ++o) CollectMarked(marks[o], result.candidates[o]);
  result.exact = internal::Merge(partials, considered, &stopper);
  if (result.exact.stopped != StopReason::kNone) result.candidates.clear();
  return result;
}

}  // namespace far
