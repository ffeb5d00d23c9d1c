// Penetration depth of two closed objects: the deepest vertex of either inside the other.
//
// Inside, exactly. A point v is strictly inside a closed mesh iff a segment from v to a point w
// outside the mesh's box crosses the mesh's triangles an odd number of times, provided every
// crossing is proper: the segment passes through a triangle's interior, with v and w strictly
// on opposite sides of its plane. Every part of that is an exact orientation predicate
// (Orient3d), so the parity is exact whenever no predicate is zero. A zero means the segment
// touches an edge, a vertex or runs in a face plane (or v lies on a face plane); then v is on
// the surface (when it lies in the closed triangle: not strictly inside; every ray finds that)
// or another w is tried, from a fixed sequence of slightly tilted rays whose ends lie on a
// parabola, which reaches one in general position within 8 T + 2 rays (FarPoints). Degenerate
// triangles (collinear corners) have no interior and cannot be crossed; they are skipped except
// to find v on the surface.
//
// Distance to the surface: the smallest TriangleDistance from v to the other mesh's triangles
// (its error bound, docs/culling.md), with a branch-and-bound descent of a TriangleBvh, whose
// boxes hold their triangles in exact arithmetic.
//
// For a closed mesh that passes through itself, "inside" is odd parity (winding number odd).
//
// Cost: a TriangleBvh of each object (n log n) per call, then for each vertex inside the
// other's box one ray (axis-aligned first: its box is thin, so the descent visits few nodes;
// a second, nearly axis-aligned one when the first is degenerate) and, for the vertices inside,
// one nearest-triangle descent, pruned by boxes and face planes and abandoned as soon as the
// vertex is shallower than the deepest so far. Two 19,800-triangle spheres, one core: about
// 30 ms per surface, then 5 ms (overlap 0.3), 30 ms (overlap 1.5) or 100 ms (one inside the
// other) (docs/contact-geometry.md, "Cost").

#include "far/pairs/penetration.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "far/base/assert.h"
#include "far/geometry/internal/predicates.h"
#include "far/geometry/triangle_contact.h"
#include "far/geometry/triangle_tests.h"
#include "far/pairs/triangle_bvh.h"

namespace far {
namespace {

using Eigen::Vector3d;
using internal::Orient3d;

// Calls visit(triangle) for every triangle whose leaf box may meet the box [lo, hi], until
// visit returns false.
template <typename Visit>
void ForEachNear(const PenetrationSurface& surface, const Vector3d& lo, const Vector3d& hi,
                 Visit&& visit) {
  if (surface.bvh.empty()) return;
  const auto& nodes = surface.bvh.nodes();
  std::vector<uint32_t> stack = {0};
  while (!stack.empty()) {
    const TriangleBvh::Node& node = nodes[stack.back()];
    stack.pop_back();
    const Eigen::Array3d far_lo = (node.center - node.half_extent).array() - surface.margin;
    const Eigen::Array3d far_hi = (node.center + node.half_extent).array() + surface.margin;
    if ((far_lo > hi.array()).any() || (far_hi < lo.array()).any()) continue;
    if (!node.leaf()) {
      stack.push_back(node.first);
      stack.push_back(node.first + 1);
      continue;
    }
    for (uint32_t k = node.first; k < node.first + node.count; ++k) {
      if (!visit(surface.bvh.order()[k])) return;
    }
  }
}

enum class Where { kInside, kOutside, kOnSurface };
enum class Ray { kGeneral, kOnSurface, kDegenerate };

// Counts the proper crossings of the segment [v, w] with the surface's triangles. kOnSurface
// when v lies on a triangle (checked on every triangle near the segment, whatever else the ray
// meets: so a point on the surface is found by its first ray), kDegenerate when the segment
// meets an edge, a vertex or a face plane in a way that a proper crossing cannot describe.
// @pre w outside the surface's box.
Ray CountCrossings(const PenetrationSurface& surface, const Vector3d& v, const Vector3d& w,
                   int& crossings) {
  crossings = 0;
  Ray verdict = Ray::kGeneral;
  ForEachNear(surface, v.cwiseMin(w), v.cwiseMax(w), [&](uint32_t t) {
    const TrianglePoints tri = surface.Triangle(t);
    const int side_v = Orient3d(tri.a, tri.b, tri.c, v);
    if (side_v == 0 && TrianglesIntersect({v, v, v}, tri)) {
      verdict = Ray::kOnSurface;
      return false;
    }
    // Once the ray is known to be degenerate only the on-surface check above matters.
    if (verdict == Ray::kDegenerate || surface.degenerate[t]) return true;
    const int side_w = Orient3d(tri.a, tri.b, tri.c, w);
    if (side_v == 0 && side_w == 0) {
      verdict = Ray::kDegenerate;  // the segment runs in the face's plane
      return true;
    }
    // v on the plane (outside the triangle) or w on it (outside the box, so outside the
    // triangle): the segment touches the plane only there and does not cross the triangle.
    if (side_v == 0 || side_w == 0 || side_v == side_w) return true;
    const int o1 = Orient3d(v, w, tri.a, tri.b);
    const int o2 = Orient3d(v, w, tri.b, tri.c);
    const int o3 = Orient3d(v, w, tri.c, tri.a);
    if ((o1 > 0 && o2 > 0 && o3 > 0) || (o1 < 0 && o2 < 0 && o3 < 0)) {
      ++crossings;
    } else if (!((o1 > 0 || o2 > 0 || o3 > 0) && (o1 < 0 || o2 < 0 || o3 < 0))) {
      verdict = Ray::kDegenerate;  // through an edge or a vertex
    }
    return true;
  });
  return verdict;
}

// The far ends of the rays from v, all in the plane x = X beyond the surface's box. Ray 0 runs
// along +x (its box is thin, so the descent visits few nodes). Ray k >= 1 ends at
//   (X, h (n_y + k), h (n_z + k^2))  with h a power of two and n_y, n_z integers near v / h,
// computed exactly (integers below 2^53 times a power of two), so these ends lie exactly on one
// parabola of the plane x = X. Why that terminates: when v is not on the surface, a ray is
// degenerate only when w lies in a face plane through v, or in the plane through v and an edge
// of a triangle whose plane misses v (v is then off that edge's line). Each such plane meets
// x = X in a line (a plane through v parallel to x = X is x = v.x < X and holds no w), so the
// degenerate ends lie on at most 4 T lines for T triangles, and a line meets a parabola in at
// most 2 points: among rays 1 .. 8 T + 1 one is in general position. h is 2^-40 of v's and the
// box's magnitude: the first tilted rays are nearly axis-aligned too.
class FarPoints {
 public:
  FarPoints(const PenetrationSurface& surface, const Vector3d& v) : v_(v) {
    const Vector3d extent = surface.box.sizes();
    const double size = extent.maxCoeff() + 1.0;
    x_ = surface.box.max().x() + size;  // > box.max().x(): coordinates are at most 3e12
    const double scale = std::max({std::abs(v.y()), std::abs(v.z()), size, 0x1p-200});
    int exponent = 0;
    std::frexp(scale, &exponent);  // scale < 2^exponent
    h_ = std::ldexp(1.0, exponent - 40);
    n_y_ = std::nearbyint(v.y() / h_);  // |n| <= 2^40
    n_z_ = std::nearbyint(v.z() / h_);
  }

  Vector3d operator()(int64_t k) const {
    if (k == 0) return {x_, v_.y(), v_.z()};
    const double kd = static_cast<double>(k);
    return {x_, h_ * (n_y_ + kd), h_ * (n_z_ + kd * kd)};
  }

  // The most rays Locate tries: 8 T + 2 (rays 0 .. 8 T + 1), enough by the argument above;
  // capped at 2^26 so that n + k^2 stays below 2^53 (exact), which covers T up to 8 million.
  static int64_t MaxRays(size_t num_triangles) {
    return std::min<int64_t>(8 * static_cast<int64_t>(num_triangles) + 2, int64_t{1} << 26);
  }

 private:
  Vector3d v_;
  double x_ = 0, h_ = 0, n_y_ = 0, n_z_ = 0;
};

Where Locate(const PenetrationSurface& surface, const Vector3d& v) {
  if (!surface.box.contains(v)) return Where::kOutside;
  const FarPoints far_points(surface, v);
  const int64_t max_rays = FarPoints::MaxRays(surface.view.triangles.size());
  for (int64_t k = 0; k < max_rays; ++k) {
    int crossings = 0;
    switch (CountCrossings(surface, v, far_points(k), crossings)) {
      case Ray::kOnSurface:
        return Where::kOnSurface;
      case Ray::kGeneral:
        return crossings % 2 == 1 ? Where::kInside : Where::kOutside;
      case Ray::kDegenerate:
        break;
    }
  }
  FAR_ASSERT(false, "no ray in general position (impossible below 8 million triangles)");
  return Where::kOutside;
}

// The distance from v to the surface (the smallest TriangleDistance over its triangles) and
// the closest point, or nullopt as soon as that distance is known to be below `stop_below` (the
// vertex cannot be the deepest). Branch and bound: nodes nearer first, a node whose box is
// farther than the best so far is skipped, and so is a triangle whose plane is (PlaneGap). Both
// bounds are shrunk by more than their rounding and than TriangleDistance's underestimate
// (32 u L), so a skipped triangle's TriangleDistance exceeds the best: the result is the minimum
// over all triangles, bit for bit.
std::optional<std::pair<double, Vector3d>> Nearest(const PenetrationSurface& surface,
                                                   const Vector3d& v, double stop_below) {
  double best = std::numeric_limits<double>::infinity();
  uint32_t best_triangle = 0;
  const auto& nodes = surface.bvh.nodes();
  std::vector<uint32_t> stack = {0};
  const auto box_distance = [&](const TriangleBvh::Node& node) {
    const Eigen::Array3d gap = ((v - node.center).cwiseAbs() - node.half_extent).array().max(0.0);
    return std::max(0.0, gap.matrix().norm() - surface.margin);
  };
  while (!stack.empty()) {
    const TriangleBvh::Node& node = nodes[stack.back()];
    stack.pop_back();
    if (box_distance(node) > best) continue;
    if (!node.leaf()) {
      const uint32_t near = node.first, far = node.first + 1;
      const bool swap = box_distance(nodes[near]) > box_distance(nodes[far]);
      stack.push_back(swap ? near : far);
      stack.push_back(swap ? far : near);
      continue;
    }
    for (uint32_t k = node.first; k < node.first + node.count; ++k) {
      const uint32_t t = surface.bvh.order()[k];
      if (surface.PlaneGap(t, v) > best) continue;
      const double d = TriangleDistance({v, v, v}, surface.Triangle(t));
      if (d < best) {
        best = d;
        best_triangle = t;
        if (best < stop_below) return std::nullopt;
      }
    }
  }
  return std::pair{best, TriangleClosestPoints({v, v, v}, surface.Triangle(best_triangle)).point_b};
}

struct Deepest {
  double depth = -1;
  uint32_t index = 0;  // of the vertex: ties go to the smallest, whatever the search order
  Vector3d vertex, surface_point;
};

// The deepest vertex of `inner` strictly inside `outer`. With seeds (the inner triangles of
// the pair's contacts), only the vertices reachable from them, and from one vertex of each
// connected part of the mesh, through vertices inside: every vertex inside is one of those
// (see MeasurePenetration's comment in the header). Without seeds, every vertex.
Deepest DeepestVertex(const PenetrationSurface& inner, const PenetrationSurface& outer,
                      std::span<const uint32_t> seed_triangles, bool use_seeds) {
  Deepest deepest;
  const auto& p = inner.view.p_WV;
  const auto consider = [&](uint32_t index) {
    const Vector3d& v = p[index];
    if (Locate(outer, v) != Where::kInside) return false;
    const auto nearest = Nearest(outer, v, deepest.depth);
    if (!nearest) return true;  // shallower than the deepest so far
    const auto& [depth, point] = *nearest;
    if (depth > deepest.depth || (depth == deepest.depth && index < deepest.index)) {
      deepest = {depth, index, v, point};
    }
    return true;
  };
  if (!use_seeds) {
    for (uint32_t v = 0; v < p.size(); ++v) consider(v);
    return deepest;
  }
  std::vector<uint8_t> queued(p.size(), 0);
  std::vector<uint32_t> queue;
  const auto push = [&](uint32_t v) {
    if (!queued[v]) {
      queued[v] = 1;
      queue.push_back(v);
    }
  };
  for (uint32_t t : seed_triangles) {
    for (uint32_t v : inner.view.triangles[t]) push(v);
  }
  for (uint32_t v : inner.part_representatives) push(v);
  while (!queue.empty()) {
    const uint32_t v = queue.back();
    queue.pop_back();
    if (!consider(v)) continue;
    for (uint32_t k = inner.neighbor_offsets[v]; k < inner.neighbor_offsets[v + 1]; ++k) {
      push(inner.neighbors[k]);
    }
  }
  return deepest;
}

}  // namespace

bool IsClosedMesh(std::span<const TriangleIndices> triangles, size_t num_vertices) {
  if (triangles.empty()) return false;
  // Every directed edge as (smaller end, larger end, direction), sorted: a closed mesh has each
  // undirected edge exactly twice, once in each direction.
  std::vector<std::tuple<uint32_t, uint32_t, bool>> edges;
  edges.reserve(3 * triangles.size());
  for (const TriangleIndices& t : triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) return false;
    for (int k = 0; k < 3; ++k) {
      const uint32_t from = t[k], to = t[(k + 1) % 3];
      if (from >= num_vertices || to >= num_vertices) return false;
      edges.emplace_back(std::min(from, to), std::max(from, to), from < to);
    }
  }
  std::sort(edges.begin(), edges.end());
  for (size_t i = 0; i < edges.size(); i += 2) {
    if (i + 1 >= edges.size()) return false;
    const auto& [a0, b0, forward0] = edges[i];
    const auto& [a1, b1, forward1] = edges[i + 1];
    if (a0 != a1 || b0 != b1 || forward0 == forward1) return false;
    if (i + 2 < edges.size() && std::get<0>(edges[i + 2]) == a0 &&
        std::get<1>(edges[i + 2]) == b0) {
      return false;  // a third use of the edge
    }
  }
  return true;
}

PenetrationSurface::PenetrationSurface(const WorldObjectView& view) : view(view) {
  bvh.Build(view.p_WV, view.triangles);
  for (const Vector3d& p : view.p_WV) box.extend(p);
  degenerate.resize(view.triangles.size());
  unit_normals.resize(view.triangles.size());
  extents.resize(view.triangles.size());
  for (size_t t = 0; t < view.triangles.size(); ++t) {
    const TrianglePoints tri = Triangle(t);
    degenerate[t] = internal::Collinear3d(tri.a, tri.b, tri.c);
    // RoundedCross: accurate to a few ulps in direction even for slivers; zero iff degenerate.
    const Vector3d normal = internal::RoundedCross(tri.a, tri.b, tri.a, tri.c);
    unit_normals[t] = degenerate[t] ? Vector3d::Zero() : Vector3d(normal.normalized());
    extents[t] = (tri.b - tri.a).cwiseAbs().sum() + (tri.c - tri.a).cwiseAbs().sum();
  }
  // Vertex neighbors (CSR) and one vertex per connected part, for the seeded search.
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  for (const TriangleIndices& t : view.triangles) {
    for (int k = 0; k < 3; ++k) {
      edges.emplace_back(t[k], t[(k + 1) % 3]);
      edges.emplace_back(t[(k + 1) % 3], t[k]);
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  neighbor_offsets.assign(view.p_WV.size() + 1, 0);
  for (const auto& [from, to] : edges) ++neighbor_offsets[from + 1];
  for (size_t v = 0; v < view.p_WV.size(); ++v) neighbor_offsets[v + 1] += neighbor_offsets[v];
  neighbors.reserve(edges.size());
  for (const auto& [from, to] : edges) neighbors.push_back(to);
  std::vector<uint8_t> reached(view.p_WV.size(), 0);
  std::vector<uint32_t> stack;
  for (uint32_t start = 0; start < view.p_WV.size(); ++start) {
    if (reached[start] || neighbor_offsets[start] == neighbor_offsets[start + 1]) continue;
    part_representatives.push_back(start);
    reached[start] = 1;
    stack.push_back(start);
    while (!stack.empty()) {
      const uint32_t v = stack.back();
      stack.pop_back();
      for (uint32_t k = neighbor_offsets[v]; k < neighbor_offsets[v + 1]; ++k) {
        if (!reached[neighbors[k]]) {
          reached[neighbors[k]] = 1;
          stack.push_back(neighbors[k]);
        }
      }
    }
  }
  // Node boxes are compared against query boxes grown by this much, which covers the rounding
  // of center +- half extent (a few ulps of the coordinates).
  margin = 0x1p-40 * (box.min().cwiseAbs().maxCoeff() + box.max().cwiseAbs().maxCoeff() + 1.0);
}

double PenetrationSurface::PlaneGap(size_t t, const Eigen::Vector3d& v) const {
  // |n . w| is within about 12 u |w| of the exact plane distance (n within a few u of the unit
  // normal, w = v - a rounded, the dot product's rounding); TriangleDistance underestimates by
  // at most 32 u L, with L (the diagonal of the box of v and the triangle) at most |w|_1 plus
  // the extent. The slack, 2^-40 = 1024 u of that sum, covers both with room to spare.
  const Vector3d w = v - view.p_WV[view.triangles[t][0]];
  return std::abs(unit_normals[t].dot(w)) - 0x1p-40 * (w.cwiseAbs().sum() + extents[t]);
}

TrianglePoints PenetrationSurface::Triangle(size_t t) const {
  const TriangleIndices& v = view.triangles[t];
  return {view.p_WV[v[0]], view.p_WV[v[1]], view.p_WV[v[2]]};
}

Penetration MeasurePenetration(const PenetrationSurface& a, const PenetrationSurface& b,
                               std::span<const ContactPair> contacts) {
  std::vector<uint32_t> seeds_a, seeds_b;
  for (const ContactPair& c : contacts) {
    seeds_a.push_back(c.triangle_a);
    seeds_b.push_back(c.triangle_b);
  }
  const bool use_seeds = !contacts.empty();
  Penetration result;
  result.closed = true;
  const Deepest b_in_a = DeepestVertex(b, a, seeds_b, use_seeds);
  const Deepest a_in_b = DeepestVertex(a, b, seeds_a, use_seeds);
  if (std::max(b_in_a.depth, a_in_b.depth) <= 0) return result;
  if (b_in_a.depth >= a_in_b.depth) {
    result.depth = b_in_a.depth;
    result.point_a = b_in_a.surface_point;
    result.point_b = b_in_a.vertex;
  } else {
    result.depth = a_in_b.depth;
    result.point_a = a_in_b.vertex;
    result.point_b = a_in_b.surface_point;
  }
  result.direction = (result.point_a - result.point_b).normalized();
  return result;
}

Penetration MeasurePenetration(const WorldObjectView& a, bool a_closed, const WorldObjectView& b,
                               bool b_closed) {
  if (!a_closed || !b_closed) return Penetration{};
  return MeasurePenetration(PenetrationSurface(a), PenetrationSurface(b), {});
}

}  // namespace far
