#include "compute_self_check.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "far/geometry/triangle_tests.h"
#include "far/pairs/triangle_bvh.h"

namespace far::internal {
namespace {

using Eigen::Vector3d;

// Objects of the check: meshes in world frame with their hierarchy topologies.
struct CheckObject {
  Mesh mesh;
  std::vector<ComputeNode> nodes;
  std::vector<uint32_t> order;
};

CheckObject MakeObject(Mesh mesh) {
  CheckObject object;
  object.mesh = std::move(mesh);
  TriangleBvh bvh;
  bvh.Build(object.mesh.p_MV, object.mesh.triangles);
  for (const TriangleBvh::Node& node : bvh.nodes())
    object.nodes.push_back({node.first, node.count});
  object.order = bvh.order();
  return object;
}

Mesh OneTriangle(const TrianglePoints& t) { return Mesh{{t.a, t.b, t.c}, {{0, 1, 2}}}; }

Vector3d Random(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return {u(rng), u(rng), u(rng)};
}

// Pairs (2i, 2i + 1) of single triangles where the filters work hardest.
std::vector<CheckObject> FilterCases() {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<CheckObject> objects;
  const auto add = [&](const TrianglePoints& s, const TrianglePoints& t) {
    objects.push_back(MakeObject(OneTriangle(s)));
    objects.push_back(MakeObject(OneTriangle(t)));
  };
  for (int i = 0; i < 1500; ++i) {  // general position
    const Vector3d c = Random(rng, 0.5);
    add({c + Random(rng, 1), c + Random(rng, 1), c + Random(rng, 1)},
        {c + Random(rng, 1), c + Random(rng, 1), c + Random(rng, 1)});
  }
  for (double offset : {0.0, 1e6}) {  // a vertex on the plane z = offset, or a double step off
    for (int i = 0; i < 600; ++i) {
      const double z = offset;
      double apex = z;
      if (i % 3 != 1) apex = std::nextafter(z, i % 3 == 0 ? -1e300 : 1e300);
      const double up = (i % 2 ? 1 : -1) * (0.1 + std::abs(u(rng)));
      add({{u(rng), u(rng), z}, {u(rng), u(rng), z}, {u(rng), u(rng), z}},
          {{u(rng) * 0.3, u(rng) * 0.3, apex}, {u(rng), u(rng), z + up}, {u(rng), u(rng), z + up}});
    }
  }
  // A vertex of t a hair off a tilted plane of s, inside s, the rest of t on one side: which
  // side the hair is on decides the answer, and no float evaluation can tell at 1e-9 (a filter
  // whose bound is too small answers at random here).
  constexpr double kHairs[] = {1e-5, 1e-7, 1e-9, 1e-11, 1e-13, 1e-15};
  for (int i = 0; i < 1200; ++i) {
    const Vector3d a = Random(rng, 1), b = Random(rng, 1), c = Random(rng, 1);
    const Vector3d n = (b - a).cross(c - a).normalized();
    if (!n.allFinite()) continue;
    const double hair = (i % 2 ? 1 : -1) * kHairs[(i / 2) % 6];
    const Vector3d on_plane = a + 0.3 * (b - a) + 0.3 * (c - a);
    const Vector3d p = on_plane + hair * n;
    const Vector3d side = 0.5 * n + Random(rng, 0.3);
    add({a, b, c}, {p, p + side + Random(rng, 0.2), p + side + Random(rng, 0.2)});
  }
  for (int i = 0; i < 500; ++i) {  // slivers
    const Vector3d a = Random(rng, 1), b = Random(rng, 1), c = Random(rng, 0.5);
    add({a, b, a + 1e-9 * (b - a) + Random(rng, 1e-9)},
        {c + Random(rng, 1), c + Random(rng, 1), c + Random(rng, 1)});
  }
  for (int i = 0; i < 500; ++i) {  // below the float filter's range: the fp64 one decides
    const Vector3d c = Vector3d(3, -2, 1) + Random(rng, 5e-14);
    add({c + Random(rng, 1e-13), c + Random(rng, 1e-13), c + Random(rng, 1e-13)},
        {c + Random(rng, 1e-13), c + Random(rng, 1e-13), c + Random(rng, 1e-13)});
  }
  return objects;
}

// A distance query's D in DistanceCases.
constexpr double kCheckDistance = 0.05;

// Pairs (2i, 2i + 1) of single triangles around a distance query's D: small triangles with
// centers up to a few D apart, and translated copies of a triangle about D away along its
// normal, at the origin and 1e6 from it: the distance cut's case.
std::vector<CheckObject> DistanceCases() {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<CheckObject> objects;
  const auto add = [&](const TrianglePoints& s, const TrianglePoints& t) {
    objects.push_back(MakeObject(OneTriangle(s)));
    objects.push_back(MakeObject(OneTriangle(t)));
  };
  for (int i = 0; i < 1000; ++i) {
    const Vector3d c = Random(rng, 0.5);
    const Vector3d d = c + Random(rng, 1).normalized() * (0.2 + 3 * kCheckDistance) * u(rng);
    add({c + Random(rng, 0.1), c + Random(rng, 0.1), c + Random(rng, 0.1)},
        {d + Random(rng, 0.1), d + Random(rng, 0.1), d + Random(rng, 0.1)});
  }
  for (int i = 0; i < 400; ++i) {
    const Vector3d a = Vector3d::Constant(i % 2 ? 1e6 : 0) + Random(rng, 0.5);
    const Vector3d b = a + Random(rng, 0.3), c = a + Random(rng, 0.3);
    // D + (k - 4) 24 eps L, k = 0..16: across the CPU's limit D + 256 eps L (at the origin;
    // 1e6 away the vertices' rounding moves the copies more than that).
    const double scale = (b - a).cwiseAbs().cwiseMax((c - a).cwiseAbs()).norm() + kCheckDistance;
    const double length = kCheckDistance + (i % 17 - 4) * 24 * std::ldexp(scale, -53);
    const Vector3d shift = (b - a).cross(c - a).normalized() * length;
    add({a, b, c}, {a + shift, b + shift, c + shift});
  }
  return objects;
}

// Meshes of small random triangles, overlapping, from a few hundred triangles to 30K (deep
// hierarchies, many descents): the traversal's case.
std::vector<CheckObject> TraversalCases() {
  std::mt19937_64 rng(7);
  std::vector<CheckObject> objects;
  for (int n : {300, 3000, 10000, 30000}) {
    Mesh mesh;
    const double size = 0.6 / std::cbrt(static_cast<double>(n));
    for (int t = 0; t < n; ++t) {
      const Vector3d c = Random(rng, 1.0);
      for (int k = 0; k < 3; ++k) mesh.p_MV.push_back(c + Random(rng, size));
      mesh.triangles.push_back({static_cast<uint32_t>(3 * t), static_cast<uint32_t>(3 * t + 1),
                                static_cast<uint32_t>(3 * t + 2)});
    }
    objects.push_back(MakeObject(std::move(mesh)));
  }
  return objects;
}

TrianglePoints Corners(const Mesh& mesh, uint32_t t) {
  const TriangleIndices& v = mesh.triangles[t];
  return {mesh.p_MV[v[0]], mesh.p_MV[v[1]], mesh.p_MV[v[2]]};
}

// A triangle's closed box (its corners' min and max: exact).
struct TriangleBoxOf {
  Eigen::AlignedBox3d box;
  uint32_t triangle = 0;
};

// Every triangle's box, sorted by its low x.
std::vector<TriangleBoxOf> SortedBoxes(const Mesh& mesh) {
  std::vector<TriangleBoxOf> boxes;
  boxes.reserve(mesh.triangles.size());
  for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    TriangleBoxOf box{Eigen::AlignedBox3d(), t};
    for (uint32_t v : mesh.triangles[t]) box.box.extend(mesh.p_MV[v]);
    boxes.push_back(box);
  }
  std::sort(boxes.begin(), boxes.end(), [](const TriangleBoxOf& x, const TriangleBoxOf& y) {
    return x.box.min().x() < y.box.min().x();
  });
  return boxes;
}

std::string Name(const SlotContact& c) {
  return std::to_string(Index(c.object_a)) + "/" + std::to_string(c.triangle_a) + " - " +
         std::to_string(Index(c.object_b)) + "/" + std::to_string(c.triangle_b);
}

// How a check's objects pair: (2i, 2i + 1), or every two.
enum class Pairing { kConsecutive, kAll };

// The object pairs `pairing` makes of `count` objects, sorted.
std::vector<SlotPair> PairsOf(size_t count, Pairing pairing) {
  std::vector<SlotPair> pairs;
  for (size_t a = 0; a < count; ++a) {
    if (pairing == Pairing::kConsecutive) {
      if (a % 2 == 1) pairs.push_back({SlotAt(a - 1), SlotAt(a)});
      continue;
    }
    for (size_t b = a + 1; b < count; ++b) pairs.push_back({SlotAt(a), SlotAt(b)});
  }
  return pairs;
}

// The objects' views, keyed from `key_base`, with pair boxes that make the pairs `pairing`
// names: a point per pair (2i, 2i + 1), or one point for all.
std::vector<ComputeObject> Views(const std::vector<CheckObject>& objects, uint64_t key_base,
                                 Pairing pairing) {
  std::vector<ComputeObject> views;
  for (size_t i = 0; i < objects.size(); ++i) {
    const CheckObject& object = objects[i];
    const Vector3d point(pairing == Pairing::kConsecutive ? static_cast<double>(i / 2) : 0.0, 0, 0);
    views.push_back({object.mesh.p_MV, object.mesh.triangles, object.nodes, object.order,
                     key_base + i, key_base + i, Eigen::AlignedBox3d(point, point)});
  }
  return views;
}

// Runs the pairs `pairing` makes of `objects` and compares with the exact predicates; "" when
// they agree.
Result<std::string> Compare(ComputeCollider& collider, const std::vector<CheckObject>& objects,
                            Pairing pairing, uint64_t key_base) {
  const std::vector<SlotPair> pairs = PairsOf(objects.size(), pairing);
  const std::vector<ComputeObject> views = Views(objects, key_base, pairing);
  ComputeQuery query;
  query.objects = views;
  auto answer = collider.Run(query);
  if (!answer) return answer.error();
  if (answer->object_pairs != pairs) return std::string("other object pairs than their boxes'");
  std::set<SlotContact> crossing, kept;
  for (const SlotContact& c : answer->crossing) {
    if (!crossing.insert(c).second || !kept.insert(c).second) return "pair " + Name(c) + " twice";
  }
  for (const SlotContact& c : answer->undecided) {
    if (!kept.insert(c).second) return "pair " + Name(c) + " twice";
  }
  for (const SlotContact& c : crossing) {
    if (!TrianglesIntersect(Corners(objects[Index(c.object_a)].mesh, c.triangle_a),
                            Corners(objects[Index(c.object_b)].mesh, c.triangle_b)))
      return "pair " + Name(c) + " certified crossing, and it does not intersect";
  }
  // Every pair whose closed boxes meet (b's boxes sorted along x: a's partners start at most
  // b's widest extent before it), then the exact predicates.
  for (const SlotPair& pair : pairs) {
    const Mesh& a = objects[Index(pair.object_a)].mesh;
    const Mesh& b = objects[Index(pair.object_b)].mesh;
    const std::vector<TriangleBoxOf> boxes_a = SortedBoxes(a), boxes_b = SortedBoxes(b);
    double widest = 0;
    for (const TriangleBoxOf& box : boxes_b)
      widest = std::max(widest, box.box.max().x() - box.box.min().x());
    for (const TriangleBoxOf& box_a : boxes_a) {
      auto k = std::lower_bound(
          boxes_b.begin(), boxes_b.end(), box_a.box.min().x() - widest,
          [](const TriangleBoxOf& box, double x) { return box.box.min().x() < x; });
      for (; k != boxes_b.end() && k->box.min().x() <= box_a.box.max().x(); ++k) {
        if (!box_a.box.intersects(k->box)) continue;
        const SlotContact c{pair.object_a, box_a.triangle, pair.object_b, k->triangle};
        if (!kept.count(c) &&
            TrianglesIntersect(Corners(a, c.triangle_a), Corners(b, c.triangle_b)))
          return "pair " + Name(c) + " intersects, and was dropped";
      }
    }
  }
  return std::string();
}

// 300 one-triangle objects whose pair boxes have small integer corners (many touch on a face,
// an edge or a corner; every 20th is empty): the object pairs must be the boxes' overlapping
// pairs, closed, as sweep-and-prune finds them. "" when they are.
Result<std::string> ComparePairs(ComputeCollider& collider, uint64_t key_base) {
  std::mt19937_64 rng(11);
  const Mesh triangle = OneTriangle({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  const std::vector<ComputeNode> leaf = {{0, 1}};
  const std::vector<uint32_t> order = {0};
  std::vector<ComputeObject> views;
  for (uint64_t i = 0; i < 300; ++i) {
    Eigen::AlignedBox3d box;  // empty
    if (i % 20 != 7) {
      const Vector3d lo(static_cast<double>(rng() % 12), static_cast<double>(rng() % 12),
                        static_cast<double>(rng() % 12));
      box = Eigen::AlignedBox3d(lo, lo + Vector3d::Constant(static_cast<double>(rng() % 3)));
    }
    views.push_back(
        {triangle.p_MV, triangle.triangles, leaf, order, key_base + i, key_base + i, box});
  }
  std::vector<SlotPair> expected;
  for (size_t a = 0; a < views.size(); ++a) {
    for (size_t b = a + 1; b < views.size(); ++b) {
      if (!views[a].pair_box.isEmpty() && views[a].pair_box.intersects(views[b].pair_box))
        expected.push_back({SlotAt(a), SlotAt(b)});
    }
  }
  ComputeQuery query;
  query.objects = views;
  auto answer = collider.Run(query);
  if (!answer) return answer.error();
  if (answer->object_pairs == expected) return std::string();
  return std::to_string(answer->object_pairs.size()) + " object pairs where the boxes make " +
         std::to_string(expected.size());
}

// Runs DistanceCases' pairs as a distance query; "" when every pair the CPU's distance test
// accepts came back.
Result<std::string> CompareDistance(ComputeCollider& collider,
                                    const std::vector<CheckObject>& objects, uint64_t key_base) {
  const std::vector<ComputeObject> views = Views(objects, key_base, Pairing::kConsecutive);
  const std::vector<SlotPair> pairs = PairsOf(objects.size(), Pairing::kConsecutive);
  ComputeQuery query;
  query.objects = views;
  query.slack = 1.0;  // every pair's boxes meet: the cut alone decides what is dropped
  query.distance = true;
  query.max_distance = kCheckDistance;
  auto answer = collider.Run(query);
  if (!answer) return answer.error();
  std::set<SlotContact> kept(answer->crossing.begin(), answer->crossing.end());
  kept.insert(answer->undecided.begin(), answer->undecided.end());
  for (const SlotPair& pair : pairs) {
    const SlotContact c{pair.object_a, 0, pair.object_b, 0};
    if (!kept.count(c) &&
        TriangleDistanceIfWithin(Corners(objects[Index(pair.object_a)].mesh, 0),
                                 Corners(objects[Index(pair.object_b)].mesh, 0), kCheckDistance))
      return "pair " + Name(c) + " is within the distance, and was dropped";
  }
  return std::string();
}

}  // namespace

Result<void> SelfCheckComputeCollider(ComputeCollider& collider) {
  // Keys far above the pipeline's own (ComputeStage counts from 1): the collider lays these
  // objects out anew, and the pipeline's objects again on its first step.
  constexpr uint64_t kKeys = uint64_t{1} << 62;
  const std::vector<CheckObject> filters = FilterCases();
  const std::vector<CheckObject> meshes = TraversalCases();
  const auto disagree = [](const char* what, const std::string& disagreement) {
    return MakeError(ErrorCode::kUnavailable,
                     std::string("gpu method: this GL driver's compute results disagree with the "
                                 "exact predicates in the self-check of ") +
                         what + " (" + disagreement +
                         "); the method is not used on it (docs/culling.md)");
  };
  for (const auto& [objects, pairing, what, keys] :
       {std::tuple{&filters, Pairing::kConsecutive, "the filters", kKeys},
        std::tuple{&meshes, Pairing::kAll, "the traversal", kKeys + (1 << 20)}}) {
    auto disagreement = Compare(collider, *objects, pairing, keys);
    if (!disagreement) return disagreement.error();
    if (!disagreement->empty()) return disagree(what, *disagreement);
  }
  auto distance = CompareDistance(collider, DistanceCases(), kKeys + (2 << 20));
  if (!distance) return distance.error();
  if (!distance->empty()) return disagree("the distance cut", *distance);
  auto object_pairs = ComparePairs(collider, kKeys + (3 << 20));
  if (!object_pairs) return object_pairs.error();
  if (!object_pairs->empty()) return disagree("the object pairs", *object_pairs);
  return {};
}

}  // namespace far::internal
