#include "far/pairs/triangle_bvh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

#include "far/pairs/internal/float_bounds.h"

namespace far {
namespace {

using internal::FloatAbove;
using internal::FloatBelow;

constexpr int kBins = 12;
constexpr double kInf = std::numeric_limits<double>::infinity();

// A closed box as min/max per axis; empty when lo > hi.
struct Box {
  double lo[3] = {kInf, kInf, kInf};
  double hi[3] = {-kInf, -kInf, -kInf};

  void Extend(const Box& other) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], other.lo[a]);
      hi[a] = std::max(hi[a], other.hi[a]);
    }
  }
  void Extend(const Eigen::Vector3d& p) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  }
  double Area() const {
    if (lo[0] > hi[0]) return 0;
    const double x = hi[0] - lo[0], y = hi[1] - lo[1], z = hi[2] - lo[2];
    return 2 * (x * y + y * z + z * x);
  }
};

Box TriangleBounds(std::span<const Eigen::Vector3d> p, const TriangleIndices& t) {
  Box box;
  for (uint32_t v : t) box.Extend(p[v]);
  return box;
}

// The node's center and half extents, rounded up so that [center - e, center + e] holds the box
// in exact arithmetic (center is rounded, so hi - center can exceed its rounded value).
void SetNodeBox(TriangleBvh::Node& node, const Box& box) {
  for (int a = 0; a < 3; ++a) {
    const double c = 0.5 * box.lo[a] + 0.5 * box.hi[a];
    const double e = std::max(box.hi[a] - c, c - box.lo[a]);
    node.center[a] = c;
    // e is within half an ulp of the exact extent; this adds at least one ulp (a cheaper
    // nextafter: e 2^-52 is between one and two ulps of e), and is > 0 even for e = 0.
    node.half_extent[a] = e + (e * 0x1p-52 + std::numeric_limits<double>::denorm_min());
  }
}

// The triangle's slabs (TriangleBvh::Slab), relative to `center`, the center of its leaf.
TriangleBvh::Slab SlabOf(std::span<const Eigen::Vector3d> p, const TriangleIndices& t,
                         const Eigen::Vector3d& center) {
  const Eigen::Vector3d& a = p[t[0]];
  const Eigen::Vector3d& b = p[t[1]];
  const Eigen::Vector3d& c = p[t[2]];
  TriangleBvh::Slab slab;
  Eigen::Vector3d normal = (b - a).cross(c - a);
  const double length = normal.norm();
  if (!(length > 0) || !std::isfinite(length)) {
    for (auto& axis : slab.axis) axis.setZero();
    return slab;
  }
  normal *= 1 / length;
  // The longest edge's direction; across it, in the triangle's plane.
  Eigen::Vector3d edge = b - a;
  if ((c - b).squaredNorm() > edge.squaredNorm()) edge = c - b;
  if ((a - c).squaredNorm() > edge.squaredNorm()) edge = a - c;
  Eigen::Vector3d across = normal.cross(edge);
  const double across_length = across.norm();
  if (across_length > 0 && std::isfinite(across_length)) {
    across *= 1 / across_length;
  } else {
    across.setZero();
  }
  // Each component rounds by at most 2^-24 of itself: scaled by 1 - 2^-22 first, the float
  // axis is shorter than the (double, unit up to a few eps) axis, so no longer than 1.
  constexpr double kShorter = 1 - 0x1p-22;
  slab.axis[0] = (kShorter * normal).cast<float>();
  slab.axis[1] = (kShorter * across).cast<float>();
  const Eigen::Vector3d ra = a - center, rb = b - center, rc = c - center;
  for (int k = 0; k < TriangleBvh::Slab::kAxes; ++k) {
    const Eigen::Vector3d axis = slab.Axis(k);
    const double da = axis.dot(ra), db = axis.dot(rb), dc = axis.dot(rc);
    slab.lo[k] = FloatBelow(std::min({da, db, dc}));
    slab.hi[k] = FloatAbove(std::max({da, db, dc}));
  }
  return slab;
}

}  // namespace

// Top-down binned-SAH build over order_[begin, end).
struct TriangleBvh::Builder {
  std::vector<Node>& nodes;
  std::vector<uint32_t>& order;
  std::vector<Box> boxes;                  // per triangle
  std::vector<Eigen::Vector3d> centroids;  // per triangle, of its box
  double area_sum = 0;
  StepStopper* stopper = nullptr;  // polled every kTrianglesPerPoll triangles sorted
  uint64_t unpolled = 0;

  // Every level of the tree passes each triangle through Split once: polling by triangles sorted
  // bounds the time between two polls, whatever the tree's shape.
  static constexpr uint64_t kTrianglesPerPoll = 1 << 15;
  bool Stopped(uint32_t triangles) {
    if (stopper == nullptr) return false;
    unpolled += triangles;
    if (unpolled < kTrianglesPerPoll) return stopper->stopped();
    unpolled = 0;
    return stopper->Poll();
  }

  // Splits [begin, end) at the best SAH bin boundary along the centroids' longest axis; returns
  // the split index, or `end` for a leaf.
  uint32_t Split(uint32_t begin, uint32_t end) {
    // Every range of at most kLeafSize triangles is a leaf, even where the SAH would split it
    // further: a simultaneous descent pays per node pair visited, and testing a few more
    // triangle boxes at a leaf costs less (far-step-profile on the paper scenes: leaves of 4 ran
    // 1.25x-1.9x faster steps than single triangles; since each leaf pair's triangles are also
    // tested along their slabs, leaves of 8 run as fast or up to 6% faster than 4, and the step
    // of breaking's break 12% faster, with half the nodes: bench/RESULTS.md, "bvh: leaves of 8").
    if (end - begin <= kLeafSize) return end;
    Box centroid_box;
    for (uint32_t i = begin; i < end; ++i) centroid_box.Extend(centroids[order[i]]);
    int axis = 0;
    for (int a = 1; a < 3; ++a) {
      if (centroid_box.hi[a] - centroid_box.lo[a] > centroid_box.hi[axis] - centroid_box.lo[axis])
        axis = a;
    }
    const double lo = centroid_box.lo[axis], extent = centroid_box.hi[axis] - lo;
    const uint32_t n = end - begin;
    if (!(extent > 0)) return begin + n / 2;  // all centroids equal
    auto bin_of = [&](uint32_t t) {
      return std::min(kBins - 1, static_cast<int>(kBins * (centroids[t][axis] - lo) / extent));
    };
    std::array<Box, kBins> bin_boxes;
    std::array<uint32_t, kBins> bin_counts{};
    for (uint32_t i = begin; i < end; ++i) {
      const int b = bin_of(order[i]);
      bin_boxes[b].Extend(boxes[order[i]]);
      bin_counts[b]++;
    }
    // Cost of splitting after bin k: area(left) n_left + area(right) n_right.
    std::array<double, kBins - 1> left_cost{};
    Box left;
    uint32_t left_count = 0;
    for (int k = 0; k < kBins - 1; ++k) {
      left.Extend(bin_boxes[k]);
      left_count += bin_counts[k];
      left_cost[k] = left.Area() * left_count;
    }
    Box right;
    uint32_t right_count = 0;
    double best_cost = kInf;
    int best = -1;
    for (int k = kBins - 1; k > 0; --k) {
      right.Extend(bin_boxes[k]);
      right_count += bin_counts[k];
      const double cost = left_cost[k - 1] + right.Area() * right_count;
      if (right_count > 0 && right_count < n && cost < best_cost) {
        best_cost = cost;
        best = k;
      }
    }
    if (best < 0) return begin + n / 2;
    const auto middle = std::partition(order.begin() + begin, order.begin() + end,
                                       [&](uint32_t t) { return bin_of(t) < best; });
    return static_cast<uint32_t>(middle - order.begin());
  }

  void Build(uint32_t node, uint32_t begin, uint32_t end) {
    if (Stopped(end - begin)) return;
    Box box;
    for (uint32_t i = begin; i < end; ++i) box.Extend(boxes[order[i]]);
    SetNodeBox(nodes[node], box);
    area_sum += box.Area();
    const uint32_t split = Split(begin, end);
    if (split == end || split == begin) {
      nodes[node].first = begin;
      nodes[node].count = end - begin;
      return;
    }
    const auto left = static_cast<uint32_t>(nodes.size());
    nodes.emplace_back();
    nodes.emplace_back();
    nodes[node].first = left;
    nodes[node].count = 0;
    Build(left, begin, split);
    Build(left + 1, split, end);
  }
};

bool TriangleBvh::Build(std::span<const Eigen::Vector3d> p_MV,
                        std::span<const TriangleIndices> triangles, StepStopper* stopper) {
  nodes_.clear();
  slabs_.clear();  // no stale slabs when there are no triangles
  order_.resize(triangles.size());
  if (triangles.empty()) return true;
  // Stopped: nothing half built is kept.
  const auto abandon = [this] {
    nodes_.clear();
    order_.clear();
    slabs_.clear();
    return false;
  };
  for (uint32_t t = 0; t < order_.size(); ++t) order_[t] = t;
  nodes_.reserve(2 * triangles.size() / kLeafSize + 2);
  Builder builder{nodes_, order_, {}, {}, 0, stopper, 0};
  builder.boxes.reserve(triangles.size());
  builder.centroids.reserve(triangles.size());
  for (const TriangleIndices& t : triangles) {
    builder.boxes.push_back(TriangleBounds(p_MV, t));
    const Box& box = builder.boxes.back();
    builder.centroids.emplace_back(0.5 * (box.lo[0] + box.hi[0]), 0.5 * (box.lo[1] + box.hi[1]),
                                   0.5 * (box.lo[2] + box.hi[2]));
    if (builder.Stopped(1)) return abandon();  // (half a second for 2M triangles)
  }
  nodes_.emplace_back();
  builder.Build(0, 0, static_cast<uint32_t>(triangles.size()));
  if (stopper != nullptr && (stopper->stopped() || stopper->Poll())) return abandon();
  built_area_ = builder.area_sum;
  slabs_.resize(order_.size());
  for (const Node& node : nodes_) {
    for (uint32_t k = node.first; k < node.first + node.count; ++k) {
      slabs_[k] = SlabOf(p_MV, triangles[order_[k]], node.center);
    }
    if (builder.Stopped(node.count)) return abandon();
  }
  return true;
}

bool TriangleBvh::Refit(std::span<const Eigen::Vector3d> p_MV,
                        std::span<const TriangleIndices> triangles, StepStopper* stopper) {
  if (nodes_.empty() || order_.size() != triangles.size()) {
    Build(p_MV, triangles, stopper);
    return true;
  }
  // Children come after their parent in nodes_: a backward sweep refits bottom-up.
  std::vector<Box> boxes(nodes_.size());
  double area = 0;
  for (size_t i = nodes_.size(); i-- > 0;) {
    const Node& node = nodes_[i];
    Box& box = boxes[i];
    if (node.leaf()) {
      for (uint32_t k = node.first; k < node.first + node.count; ++k) {
        box.Extend(TriangleBounds(p_MV, triangles[order_[k]]));
      }
    } else {
      box = boxes[node.first];
      box.Extend(boxes[node.first + 1]);
    }
    SetNodeBox(nodes_[i], box);
    area += box.Area();
  }
  if (area > kRebuildGrowth * built_area_) {
    Build(p_MV, triangles, stopper);
    return true;
  }
  // Their memory too (40 bytes a triangle): a deformable object refits from now on, and the
  // gpu method keeps a refit copy of each deformable object's hierarchy only for its boxes.
  std::vector<Slab>().swap(slabs_);
  return false;
}

}  // namespace far
