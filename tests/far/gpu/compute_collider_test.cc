// The gpu method's kernels on their own (label gpu; llvmpipe in CI): the float and fp64 filters
// against the exact predicates on pairs of single triangles, random and at the bound (a
// rounding away from touching, far from the origin, slivers), and the traversal against brute
// force on meshes with hierarchies.
#include "far/gpu/compute_collider.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "far/geometry/triangle_tests.h"
#include "far/gpu/gl_context.h"
#include "far/model/world_vertex.h"
#include "far/pairs/sweep_and_prune.h"
#include "far/pairs/triangle_bvh.h"

namespace far {
namespace {

using Eigen::Vector3d;

// One object per triangle: a one-leaf hierarchy.
struct TriangleObjects {
  std::vector<std::vector<Vector3d>> vertices;
  std::vector<TriangleIndices> triangle = {{0, 1, 2}};
  std::vector<ComputeNode> leaf = {{0, 1}};
  std::vector<uint32_t> order = {0};
  std::vector<ComputeObject> objects;

  void Add(const TrianglePoints& t) { vertices.push_back({t.a, t.b, t.c}); }
  // Objects (2i, 2i + 1): the pairs as they were added.
  std::vector<SlotPair> Pairs() const {
    std::vector<SlotPair> pairs;
    for (size_t i = 0; i + 1 < vertices.size(); i += 2) pairs.push_back({SlotAt(i), SlotAt(i + 1)});
    return pairs;
  }
  // Pair boxes that make the pairs (2i, 2i + 1) the object pairs: a point at x = i each.
  std::span<const ComputeObject> Views(uint64_t world_key) {
    objects.clear();
    for (size_t i = 0; i < vertices.size(); ++i) {
      const Vector3d point(static_cast<double>(i / 2), 0, 0);
      objects.push_back({vertices[i], triangle, leaf, order, i + 1, world_key,
                         Eigen::AlignedBox3d(point, point)});
    }
    return objects;
  }
};

class ComputeColliderTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto context = GlContext::Create();
    ASSERT_TRUE(context.ok()) << ToString(context.error());
    context_ = std::move(*context).release();
    auto collider = ComputeCollider::Create();
    ASSERT_TRUE(collider.ok()) << ToString(collider.error());
    collider_ = std::move(*collider).release();
  }
  static void TearDownTestSuite() {
    delete collider_;
    delete context_;
  }

  // Runs pairs (2i, 2i + 1) of `triangles` and checks each against TrianglesIntersect: a
  // crossing pair must intersect, and no intersecting pair may be dropped. Returns the answer.
  ComputeAnswer CheckPairs(TriangleObjects& triangles) {
    const std::vector<SlotPair> pairs = triangles.Pairs();
    ComputeQuery query;
    query.objects = triangles.Views(++world_key_);
    auto answer = collider_->Run(query);
    EXPECT_TRUE(answer.ok()) << ToString(answer.error());
    if (!answer.ok()) return {};
    EXPECT_EQ(answer->object_pairs, pairs);
    std::set<size_t> crossing, undecided;
    for (const SlotContact& c : answer->crossing) crossing.insert(Index(c.object_a) / 2);
    for (const SlotContact& c : answer->undecided) undecided.insert(Index(c.object_a) / 2);
    for (size_t p = 0; p < pairs.size(); ++p) {
      const auto& s = triangles.vertices[2 * p];
      const auto& t = triangles.vertices[2 * p + 1];
      const bool exact = TrianglesIntersect({s[0], s[1], s[2]}, {t[0], t[1], t[2]});
      EXPECT_FALSE(crossing.count(p) && undecided.count(p)) << "pair " << p << " twice";
      if (exact) {
        EXPECT_TRUE(crossing.count(p) || undecided.count(p)) << "pair " << p << " dropped";
      } else {
        EXPECT_FALSE(crossing.count(p)) << "pair " << p << " called crossing";
      }
    }
    return std::move(*answer);
  }

  static inline GlContext* context_ = nullptr;
  static inline ComputeCollider* collider_ = nullptr;
  uint64_t world_key_ = 0;
};

Vector3d RandomPoint(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return {u(rng), u(rng), u(rng)};
}

// The objects whose pair boxes meet (closed), by brute force.
std::vector<SlotPair> PairsOfBoxes(std::span<const ComputeObject> objects) {
  std::vector<SlotPair> pairs;
  for (size_t a = 0; a < objects.size(); ++a) {
    for (size_t b = a + 1; b < objects.size(); ++b) {
      if (!objects[a].pair_box.isEmpty() && objects[a].pair_box.intersects(objects[b].pair_box))
        pairs.push_back({SlotAt(a), SlotAt(b)});
    }
  }
  return pairs;
}

// The box of a mesh's vertices.
Eigen::AlignedBox3d BoxOf(const Mesh& mesh) {
  Eigen::AlignedBox3d box;
  for (const Vector3d& p : mesh.p_MV) box.extend(p);
  return box;
}

// The hierarchy TriangleBvh builds over `mesh`, as a ComputeObject takes it (without its boxes).
bool BuildTopology(const Mesh& mesh, std::vector<ComputeNode>& nodes,
                   std::vector<uint32_t>& order) {
  TriangleBvh bvh;
  if (!bvh.Build(mesh.p_MV, mesh.triangles)) return false;
  for (const auto& node : bvh.nodes()) nodes.push_back({node.first, node.count});
  order = bvh.order();
  return true;
}

// Runs the collider on `objects` (meshes[i]'s views, their pair boxes the meshes' boxes) and
// checks that the object pairs are the boxes' and that every intersecting triangle pair is kept
// (crossing or undecided) and none twice, and that the PCS is the triangles of the kept pairs,
// by slot; returns how many intersect, and the answer in `answer_out` when given.
int ExpectEveryIntersectingPairKept(ComputeCollider& collider,
                                    std::span<const ComputeObject> objects,
                                    const std::vector<Mesh>& meshes, const std::string& where,
                                    ComputeAnswer* answer_out = nullptr) {
  ComputeQuery query;
  query.objects = objects;
  auto answer = collider.Run(query);
  EXPECT_TRUE(answer.ok()) << ToString(answer.error());
  if (!answer.ok()) return 0;
  if (answer_out != nullptr) *answer_out = *answer;
  const std::vector<SlotPair> pairs = PairsOfBoxes(objects);
  EXPECT_EQ(answer->object_pairs, pairs) << where;
  std::set<SlotContact> found;
  std::vector<std::vector<uint32_t>> pcs(objects.size());
  for (const auto* list : {&answer->crossing, &answer->undecided}) {
    for (const SlotContact& c : *list) {
      EXPECT_TRUE(found.insert(c).second) << where << ": twice";
      pcs[Index(c.object_a)].push_back(c.triangle_a);
      pcs[Index(c.object_b)].push_back(c.triangle_b);
    }
  }
  // The slots' triangles share the GPU's words of PCS bits (objects of 1 to 300 triangles):
  // no slot may get another's.
  for (auto& triangles : pcs) {
    std::sort(triangles.begin(), triangles.end());
    triangles.erase(std::unique(triangles.begin(), triangles.end()), triangles.end());
  }
  answer->pcs.resize(objects.size());
  EXPECT_EQ(answer->pcs, pcs) << where << ": the PCS is not the kept pairs' triangles";
  int intersecting = 0;
  for (const SlotPair& pair : pairs) {
    const Mesh& a = meshes[Index(pair.object_a)];
    const Mesh& b = meshes[Index(pair.object_b)];
    for (uint32_t i = 0; i < a.triangles.size(); ++i) {
      for (uint32_t j = 0; j < b.triangles.size(); ++j) {
        const auto& s = a.triangles[i];
        const auto& t = b.triangles[j];
        if (!TrianglesIntersect({a.p_MV[s[0]], a.p_MV[s[1]], a.p_MV[s[2]]},
                                {b.p_MV[t[0]], b.p_MV[t[1]], b.p_MV[t[2]]}))
          continue;
        ++intersecting;
        EXPECT_TRUE(found.count({pair.object_a, i, pair.object_b, j}))
            << where << ": " << Index(pair.object_a) << "/" << i << " - " << Index(pair.object_b)
            << "/" << j << " missed";
      }
    }
  }
  return intersecting;
}

TEST_F(ComputeColliderTest, FiltersAgreeWithTheExactPredicatesOnRandomPairs) {
  std::mt19937_64 rng(42);
  TriangleObjects triangles;
  for (int i = 0; i < 4000; ++i) {
    const Vector3d center = RandomPoint(rng, 0.5);
    triangles.Add(
        {center + RandomPoint(rng, 1), center + RandomPoint(rng, 1), center + RandomPoint(rng, 1)});
    triangles.Add(
        {center + RandomPoint(rng, 1), center + RandomPoint(rng, 1), center + RandomPoint(rng, 1)});
  }
  const ComputeAnswer answer = CheckPairs(triangles);
  EXPECT_GT(answer.crossing.size(), 400u) << "general position: most crossings certified";
  EXPECT_GT(answer.float_decided, answer.box_pairs * 9 / 10);
}

// At the bound: a vertex of t exactly on s's plane (touching), or one double step above or below
// it, at the origin and 1e6 and 1e11 away from it (the plane z = offset is exact there). Every
// such pair must come out as the exact predicates say: touching pairs are crossing or undecided,
// a pair a rounding away from touching is never called crossing unless it crosses.
TEST_F(ComputeColliderTest, PairsARoundingAwayFromTouching) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  TriangleObjects triangles;
  for (double offset : {0.0, 1e6, 1e11}) {
    for (int i = 0; i < 600; ++i) {
      const double z = offset;
      const TrianglePoints s{{u(rng), u(rng), z}, {u(rng), u(rng), z}, {u(rng), u(rng), z}};
      const int step = i % 3 - 1;  // -1, 0, +1 double steps off the plane
      double apex = z;
      if (step != 0) apex = std::nextafter(z, step > 0 ? 1e300 : -1e300);
      const Vector3d top{u(rng) * 0.3, u(rng) * 0.3, apex};
      const double up = (i % 2 ? 1 : -1) * (0.1 + std::abs(u(rng)));
      triangles.Add(s);
      triangles.Add({top, {u(rng), u(rng), z + up}, {u(rng), u(rng), z + up}});
    }
  }
  const ComputeAnswer answer = CheckPairs(triangles);
  EXPECT_GT(answer.undecided.size(), 0u) << "touching pairs are never certified";
}

// A vertex of t a hair (1e-5 to 1e-15) off the tilted plane of s, inside s, the rest of t on
// one side: the side of the hair decides, and float cannot tell below about 1e-7: a filter
// whose bound were too small would answer these at random (the self-check holds every driver
// to the same cases: far/pipeline/src/compute_self_check.cc).
TEST_F(ComputeColliderTest, AVertexAHairOffATiltedPlane) {
  std::mt19937_64 rng(13);
  constexpr double kHairs[] = {1e-5, 1e-7, 1e-9, 1e-11, 1e-13, 1e-15};
  TriangleObjects triangles;
  for (int i = 0; i < 2400; ++i) {
    const Vector3d a = RandomPoint(rng, 1), b = RandomPoint(rng, 1), c = RandomPoint(rng, 1);
    const Vector3d n = (b - a).cross(c - a).normalized();
    const double hair = (i % 2 ? 1 : -1) * kHairs[(i / 2) % 6];
    const Vector3d p = a + 0.3 * (b - a) + 0.3 * (c - a) + hair * n;
    const Vector3d side = 0.5 * n + RandomPoint(rng, 0.3);
    triangles.Add({a, b, c});
    triangles.Add({p, p + side + RandomPoint(rng, 0.2), p + side + RandomPoint(rng, 0.2)});
  }
  const ComputeAnswer answer = CheckPairs(triangles);
  EXPECT_GT(answer.double_decided, 100) << "the hairs below float's reach are decided in fp64";
}

// Slivers (one edge 1e-9 of the others) crossing ordinary triangles, and tiny triangles whose
// differences are below the float filter's range (2^-40): the fp64 filter decides those.
TEST_F(ComputeColliderTest, SliversAndTinyTrianglesGoToTheFp64Filter) {
  std::mt19937_64 rng(12);
  TriangleObjects triangles;
  for (int i = 0; i < 1000; ++i) {
    const Vector3d a = RandomPoint(rng, 1), b = RandomPoint(rng, 1);
    triangles.Add({a, b, a + 1e-9 * (b - a) + RandomPoint(rng, 1e-9)});
    const Vector3d c = RandomPoint(rng, 0.5);
    triangles.Add({c + RandomPoint(rng, 1), c + RandomPoint(rng, 1), c + RandomPoint(rng, 1)});
  }
  for (int i = 0; i < 1000; ++i) {
    const double scale = 1e-13;
    const Vector3d c = Vector3d(3, -2, 1) + RandomPoint(rng, 0.5 * scale);
    triangles.Add(
        {c + RandomPoint(rng, scale), c + RandomPoint(rng, scale), c + RandomPoint(rng, scale)});
    triangles.Add(
        {c + RandomPoint(rng, scale), c + RandomPoint(rng, scale), c + RandomPoint(rng, scale)});
  }
  const ComputeAnswer answer = CheckPairs(triangles);
  EXPECT_GT(answer.double_decided, 500) << "the tiny pairs are decided in fp64";
}

// A translated copy of `s` this far along its normal lies D + (k - 4) 24 eps L from it (L: the
// pair's scale, as TriangleDistanceIfWithin measures it; eps = 2^-53): k = 0..16 straddles
// the CPU's limit D + 256 eps L, so a GPU cut without the CPU's slack drops some it accepts.
double ShiftAroundTheCpusLimit(double D, const TrianglePoints& s, int k) {
  Eigen::AlignedBox3d box;
  for (const Vector3d& p : {s.a, s.b, s.c}) box.extend(p);
  const double L = box.diagonal().norm() + D;
  return D + (k - 4) * 24 * std::ldexp(L, -53);
}

// Pairs at distances around D for a distance query: random small triangles with centers up to
// a few D apart, translated copies of a triangle D + (k - 4) 24 eps L along its normal (around
// the CPU's limit, ShiftAroundTheCpusLimit), slivers beside a plane at D, at the origin and 1e6
// from it.
// Every pair the CPU's distance test accepts must come back (crossing or undecided), and most
// of those it rejects must be dropped on the GPU.
TEST_F(ComputeColliderTest, ADistanceQueryDropsOnlyPairsTheCpuWouldReject) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> u(0, 1);
  for (double D : {0.01, 0.2}) {
    TriangleObjects triangles;
    for (double origin : {0.0, 1e6}) {
      const Vector3d o(origin, -origin, origin);
      for (int i = 0; i < 800; ++i) {
        const Vector3d c = o + RandomPoint(rng, 0.5);
        const Vector3d d = c + RandomPoint(rng, 1).normalized() * (0.2 + 3 * D) * u(rng);
        triangles.Add(
            {c + RandomPoint(rng, 0.1), c + RandomPoint(rng, 0.1), c + RandomPoint(rng, 0.1)});
        triangles.Add(
            {d + RandomPoint(rng, 0.1), d + RandomPoint(rng, 0.1), d + RandomPoint(rng, 0.1)});
      }
      for (int i = 0; i < 340; ++i) {
        const Vector3d a = o + RandomPoint(rng, 0.5), b = a + RandomPoint(rng, 0.3),
                       c = a + RandomPoint(rng, 0.3);
        const Vector3d n = (b - a).cross(c - a).normalized();
        triangles.Add({a, b, c});
        const Vector3d shift = n * ShiftAroundTheCpusLimit(D, {a, b, c}, i % 17);
        triangles.Add({a + shift, b + shift, c + shift});
      }
      for (int i = 0; i < 200; ++i) {
        const Vector3d a = o + RandomPoint(rng, 0.5), b = a + RandomPoint(rng, 0.3);
        const double z = a.z() - D * (0.99 + 0.02 * u(rng));
        triangles.Add({a, b, a + 1e-9 * (b - a) + RandomPoint(rng, 1e-9)});
        triangles.Add({Vector3d(a.x() - 1, a.y() - 1, z), Vector3d(a.x() + 1, a.y() - 1, z),
                       Vector3d(a.x(), a.y() + 2, z)});
      }
    }
    const std::vector<SlotPair> pairs = triangles.Pairs();
    ComputeQuery query;
    query.objects = triangles.Views(++world_key_);
    query.slack = 1.0;  // wide: every pair the CPU accepts has boxes within it
    query.distance = true;
    query.max_distance = D;
    auto answer = collider_->Run(query);
    ASSERT_TRUE(answer.ok()) << ToString(answer.error());
    std::set<size_t> kept;
    for (const auto* list : {&answer->crossing, &answer->undecided}) {
      for (const SlotContact& c : *list) kept.insert(Index(c.object_a) / 2);
    }
    int accepted = 0, rejected = 0, rejected_kept = 0;
    for (size_t p = 0; p < pairs.size(); ++p) {
      const auto& s = triangles.vertices[2 * p];
      const auto& t = triangles.vertices[2 * p + 1];
      if (TriangleDistanceIfWithin({s[0], s[1], s[2]}, {t[0], t[1], t[2]}, D)) {
        ++accepted;
        EXPECT_TRUE(kept.count(p))
            << "D " << D << ": pair " << p << " accepted by the CPU, dropped";
      } else {
        ++rejected;
        rejected_kept += static_cast<int>(kept.count(p));
      }
    }
    EXPECT_GT(accepted, 300) << "D " << D;
    EXPECT_EQ(answer->distance_culled, static_cast<int64_t>(pairs.size() - kept.size()));
    EXPECT_LT(rejected_kept, rejected / 4)
        << "D " << D << ": the GPU should drop most of the pairs the CPU rejects";
  }
}

// Meshes of random triangles with their hierarchies: every intersecting triangle pair of every
// object pair is found (crossing or undecided), none twice.
TEST_F(ComputeColliderTest, TraversalFindsEveryIntersectingPairOfMeshes) {
  std::mt19937_64 rng(7);
  int expected = 0;
  for (int scene = 0; scene < 12; ++scene) {
    const int num_objects = 2 + scene % 5;
    std::vector<Mesh> meshes(num_objects);
    std::vector<std::vector<ComputeNode>> nodes(num_objects);
    std::vector<std::vector<uint32_t>> orders(num_objects);
    std::vector<ComputeObject> objects(num_objects);
    for (int o = 0; o < num_objects; ++o) {
      const int n = 1 + static_cast<int>(rng() % 300);
      const Vector3d center = RandomPoint(rng, 1.0);
      for (int t = 0; t < n; ++t) {
        const Vector3d c = center + RandomPoint(rng, 0.8);
        for (int k = 0; k < 3; ++k) meshes[o].p_MV.push_back(c + RandomPoint(rng, 0.15));
        meshes[o].triangles.push_back({static_cast<uint32_t>(3 * t),
                                       static_cast<uint32_t>(3 * t + 1),
                                       static_cast<uint32_t>(3 * t + 2)});
      }
      ASSERT_TRUE(BuildTopology(meshes[o], nodes[o], orders[o]));
      objects[o] = {meshes[o].p_MV,
                    meshes[o].triangles,
                    nodes[o],
                    orders[o],
                    static_cast<uint64_t>(100 * scene + o + 1),
                    ++world_key_,
                    BoxOf(meshes[o])};
    }
    expected += ExpectEveryIntersectingPairKept(*collider_, objects, meshes,
                                                "scene " + std::to_string(scene));
  }
  EXPECT_GT(expected, 200) << "the scenes should have many intersecting pairs to find";
}

// Two grids of 300 slivers, one along x and one along y, each tilted at random across z = 0:
// every box of one meets every box of the other, 90,000 pairs whose boxes meet, more than the
// candidates' first buffer holds (65,536), so it grows and the kernels run again; every
// intersecting pair is still found, and the next step needs one run.
TEST_F(ComputeColliderTest, MorePairsOfBoxesThanTheFirstBufferHolds) {
  std::mt19937_64 rng(57);
  std::uniform_real_distribution<double> u(-0.01, 0.01);
  constexpr int kSlivers = 300;
  std::vector<Mesh> meshes(2);
  for (int o = 0; o < 2; ++o) {
    for (int i = 0; i < kSlivers; ++i) {
      const double across = (i + 0.5) / kSlivers;
      // Along x for object 0, along y for object 1, spanning [0, 1] and z in [-0.01, 0.01].
      const auto at = [&](double along, double side, double z) {
        return o == 0 ? Vector3d(along, side, z) : Vector3d(side, along, z);
      };
      // One end below z = 0, the other above: every box holds z = 0.
      meshes[o].p_MV.push_back(at(0, across, -std::abs(u(rng))));
      meshes[o].p_MV.push_back(at(1, across, std::abs(u(rng))));
      meshes[o].p_MV.push_back(at(0.5, across + 0.4 / kSlivers, u(rng)));
      meshes[o].triangles.push_back({static_cast<uint32_t>(3 * i), static_cast<uint32_t>(3 * i + 1),
                                     static_cast<uint32_t>(3 * i + 2)});
    }
  }
  std::vector<std::vector<ComputeNode>> nodes(2);
  std::vector<std::vector<uint32_t>> orders(2);
  std::vector<ComputeObject> objects(2);
  for (int o = 0; o < 2; ++o) {
    ASSERT_TRUE(BuildTopology(meshes[o], nodes[o], orders[o]));
    objects[o] = {meshes[o].p_MV,  meshes[o].triangles, nodes[o],        orders[o],
                  uint64_t(o + 1), uint64_t(o + 1),     BoxOf(meshes[o])};
  }
  auto collider = ComputeCollider::Create();  // its buffers as small as at first
  ASSERT_TRUE(collider.ok()) << ToString(collider.error());
  ComputeAnswer answer;
  const int intersecting =
      ExpectEveryIntersectingPairKept(**collider, objects, meshes, "first step", &answer);
  EXPECT_EQ(answer.box_pairs, kSlivers * kSlivers);
  EXPECT_GT(answer.runs, 1) << "the candidates' buffer should have grown";
  EXPECT_GT(intersecting, 1000);
  ExpectEveryIntersectingPairKept(**collider, objects, meshes, "second step", &answer);
  EXPECT_EQ(answer.runs, 1);
}

// Steps where only some objects move: the others keep the boxes and hierarchies computed when
// they last moved, and every step still finds every intersecting pair. The same objects move
// on several steps in a row (the refit's plan is reused) and then others (it is made again).
TEST_F(ComputeColliderTest, ObjectsThatDidNotMoveKeepTheirBoxes) {
  std::mt19937_64 rng(21);
  constexpr int kObjects = 4;
  std::vector<Mesh> meshes(kObjects);
  std::vector<std::vector<ComputeNode>> nodes(kObjects);
  std::vector<std::vector<uint32_t>> orders(kObjects);
  std::vector<uint64_t> world(kObjects, 0);
  for (int o = 0; o < kObjects; ++o) {
    const int n = 50 + 40 * o;
    for (int t = 0; t < n; ++t) {
      const Vector3d c = RandomPoint(rng, 1.0);
      for (int k = 0; k < 3; ++k) meshes[o].p_MV.push_back(c + RandomPoint(rng, 0.2));
      meshes[o].triangles.push_back({static_cast<uint32_t>(3 * t), static_cast<uint32_t>(3 * t + 1),
                                     static_cast<uint32_t>(3 * t + 2)});
    }
    ASSERT_TRUE(BuildTopology(meshes[o], nodes[o], orders[o]));
  }
  int found_total = 0;
  // Object 0 never moves; the others move on the steps that name them (vertices shifted and
  // jittered).
  const std::vector<std::vector<int>> moving = {{1, 2, 3}, {2},    {1},    {1}, {1},
                                                {3},       {1, 2}, {1, 2}, {2}, {1, 2}};
  for (size_t step = 0; step < moving.size(); ++step) {
    for (int o : moving[step]) {
      const Vector3d shift = RandomPoint(rng, 0.3);
      for (Vector3d& p : meshes[o].p_MV) p += shift + RandomPoint(rng, 0.01);
      world[o] = 100 * step + o + 1;
    }
    if (step == 0) world[0] = 1;
    std::vector<ComputeObject> objects(kObjects);
    for (int o = 0; o < kObjects; ++o) {
      objects[o] = {meshes[o].p_MV,  meshes[o].triangles,          nodes[o],
                    orders[o],       static_cast<uint64_t>(o + 1), world[o],
                    BoxOf(meshes[o])};
    }
    found_total += ExpectEveryIntersectingPairKept(*collider_, objects, meshes,
                                                   "step " + std::to_string(step));
  }
  EXPECT_GT(found_total, 50);
}

// The device places posed objects' vertices itself: its placement kernel gave WorldVertex's
// doubles, bit for bit, on Create's probe (every GL 4.5 device with fp64 that honours `precise`
// does; one that fused or reordered the sums would fall back to uploads, and this would say so).
TEST_F(ComputeColliderTest, TheDevicePlacesPosedObjectsExactly) {
  EXPECT_TRUE(collider_->PlacesOnGpu());
}

// Objects of `triangles[o]` separate random triangles each (corners within `size` of a center
// within 0.5 of the origin), in their own frames, with their hierarchies' topologies.
struct RandomObjects {
  std::vector<Mesh> meshes;
  std::vector<std::vector<ComputeNode>> nodes;
  std::vector<std::vector<uint32_t>> orders;
};
RandomObjects MakeRandomObjects(std::mt19937_64& rng, const std::vector<int>& triangles,
                                double size) {
  RandomObjects made;
  for (int n : triangles) {
    Mesh& mesh = made.meshes.emplace_back();
    for (int t = 0; t < n; ++t) {
      const Vector3d c = RandomPoint(rng, 0.5);
      for (int k = 0; k < 3; ++k) mesh.p_MV.push_back(c + RandomPoint(rng, size));
      mesh.triangles.push_back({static_cast<uint32_t>(3 * t), static_cast<uint32_t>(3 * t + 1),
                                static_cast<uint32_t>(3 * t + 2)});
    }
    EXPECT_TRUE(BuildTopology(mesh, made.nodes.emplace_back(), made.orders.emplace_back()));
  }
  return made;
}

// Rigid objects at random poses over several steps (object 0 holds still on odd steps, object 2
// changes its own vertices at step 4): placed on the GPU from their poses, the collider gives
// the very answer another gives when their world vertices are uploaded, finds every
// intersecting pair, and uploads less.
TEST_F(ComputeColliderTest, PosedObjectsPlacedOnTheGpuFindWhatUploadedOnesFind) {
  std::mt19937_64 rng(77);
  constexpr int kObjects = 5;
  auto [meshes, nodes, orders] = MakeRandomObjects(rng, {40, 70, 100, 130, 160}, 0.15);
  std::vector<Mesh> world(kObjects);
  std::vector<uint64_t> model_key = {1, 2, 3, 4, 5}, world_key(kObjects);
  std::vector<Eigen::Isometry3d> X_WM(kObjects);
  auto placing = ComputeCollider::Create();
  auto uploading = ComputeCollider::Create();
  ASSERT_TRUE(placing.ok() && uploading.ok());
  ASSERT_TRUE((*placing)->PlacesOnGpu());
  for (int step = 0; step < 8; ++step) {
    if (step == 4) {
      for (Vector3d& p : meshes[2].p_MV) p += RandomPoint(rng, 0.02);
      model_key[2] = 100;
    }
    int64_t moved_vertices = 0;
    for (int o = 0; o < kObjects; ++o) {
      if (o == 0 && step % 2 == 1) continue;  // holds still: nothing of it is uploaded or placed
      Eigen::Quaterniond q(RandomPoint(rng, 1.0).norm() + 0.1, RandomPoint(rng, 1.0).x(),
                           RandomPoint(rng, 1.0).y(), RandomPoint(rng, 1.0).z());
      X_WM[o] = Eigen::Translation3d(RandomPoint(rng, 0.6)) * q.normalized();
      world[o] = {{}, meshes[o].triangles};
      for (const Vector3d& p : meshes[o].p_MV) world[o].p_MV.push_back(WorldVertex(X_WM[o], p));
      world_key[o] = static_cast<uint64_t>(100 * step + o + 1);
      moved_vertices += static_cast<int64_t>(meshes[o].p_MV.size());
    }
    std::vector<ComputeObject> placed(kObjects), uploaded(kObjects);
    for (int o = 0; o < kObjects; ++o) {
      uploaded[o] = {world[o].p_MV,   world[o].triangles, nodes[o],       orders[o],
                     uint64_t(o + 1), world_key[o],       BoxOf(world[o])};
      placed[o] = uploaded[o];
      placed[o].p_MV = meshes[o].p_MV;
      placed[o].X_WM = X_WM[o].matrix().topRows<3>();
      placed[o].model_key = model_key[o];
    }
    const std::string where = "step " + std::to_string(step);
    ComputeAnswer by_pose, by_upload;
    ExpectEveryIntersectingPairKept(**placing, placed, world, where, &by_pose);
    ExpectEveryIntersectingPairKept(**uploading, uploaded, world, where, &by_upload);
    EXPECT_EQ(by_pose.vertices_placed, moved_vertices) << where;
    EXPECT_EQ(by_upload.vertices_placed, 0) << where;
    if (step > 0 && step != 4) {
      EXPECT_LT(by_pose.bytes_uploaded, by_upload.bytes_uploaded) << where;
    }
    for (ComputeAnswer* answer : {&by_pose, &by_upload}) {
      std::sort(answer->crossing.begin(), answer->crossing.end());
      std::sort(answer->undecided.begin(), answer->undecided.end());
    }
    EXPECT_EQ(by_pose.object_pairs, by_upload.object_pairs) << where;
    EXPECT_EQ(by_pose.crossing, by_upload.crossing) << where;
    EXPECT_EQ(by_pose.undecided, by_upload.undecided) << where;
    EXPECT_EQ(by_pose.pcs, by_upload.pcs) << where;
  }
}

// A layout made without posed objects has no room for their own vertices on the GPU: an
// object posed later is uploaded as its world vertices, with the same answer, until the layout
// changes and makes room.
TEST_F(ComputeColliderTest, ObjectsPosedAfterTheLayoutWasMadeAreUploadedUntilItChanges) {
  std::mt19937_64 rng(78);
  constexpr int kObjects = 2;
  // 900 vertices each: more than the device check's probe left room for.
  const auto [meshes, nodes, orders] = MakeRandomObjects(rng, {300, 300}, 0.1);
  std::vector<Mesh> world(kObjects);
  auto collider = ComputeCollider::Create();
  ASSERT_TRUE(collider.ok());
  // Step 0 at the identity pose; steps 1 and 2 posed, step 2 with new topology keys.
  const int64_t expected_placed[] = {0, 0, 2 * 900};
  for (int step = 0; step < 3; ++step) {
    std::vector<ComputeObject> objects(kObjects);
    for (int o = 0; o < kObjects; ++o) {
      Eigen::Isometry3d X_WM = Eigen::Isometry3d::Identity();
      if (step > 0)
        X_WM = Eigen::Translation3d(RandomPoint(rng, 0.2)) *
               Eigen::AngleAxisd(0.3 * step + o, Vector3d::UnitZ());
      world[o] = {{}, meshes[o].triangles};
      for (const Vector3d& p : meshes[o].p_MV) world[o].p_MV.push_back(WorldVertex(X_WM, p));
      objects[o] = {world[o].p_MV,
                    world[o].triangles,
                    nodes[o],
                    orders[o],
                    static_cast<uint64_t>(step == 2 ? 10 + o : 1 + o),
                    static_cast<uint64_t>(10 * step + o + 1),
                    BoxOf(world[o])};
      if (step > 0) {
        objects[o].p_MV = meshes[o].p_MV;
        objects[o].X_WM = X_WM.matrix().topRows<3>();
        objects[o].model_key = static_cast<uint64_t>(o + 1);
      }
    }
    ComputeAnswer answer;
    const std::string where = "step " + std::to_string(step);
    EXPECT_GT(ExpectEveryIntersectingPairKept(**collider, objects, world, where, &answer), 0)
        << where;
    EXPECT_EQ(answer.vertices_placed, expected_placed[step]) << where;
  }
}

// The object pairs are sweep-and-prune's for the same boxes and margin: boxes with small integer
// corners (many touch on a face, an edge or a corner), some empty or not finite, some objects
// without triangles (paired, never descended), at margins 0 and 1; 2,000 objects make over
// 4,096 pairs, so the pair buffer grows and the kernels run again.
TEST_F(ComputeColliderTest, ObjectPairsAreThoseSweepAndPruneFinds) {
  std::mt19937_64 rng(31);
  const std::vector<Vector3d> vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<TriangleIndices> triangle = {{0, 1, 2}};
  const std::vector<ComputeNode> leaf = {{0, 1}};
  const std::vector<uint32_t> order = {0};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const int num_objects : {3, 70, 2000}) {
    for (const double margin : {0.0, 1.0}) {
      std::vector<SlotBox> boxes;
      std::vector<ComputeObject> objects;
      for (int o = 0; o < num_objects; ++o) {
        const double extent = num_objects < 100 ? 4 : 24;
        const Vector3d lo(static_cast<double>(rng() % 40), static_cast<double>(rng() % 40),
                          static_cast<double>(rng() % 40));
        Eigen::AlignedBox3d box(
            lo, lo + Vector3d::Constant(static_cast<double>(rng() % 5) * extent / 4));
        if (o % 31 == 5) box = Eigen::AlignedBox3d();  // empty
        if (o % 37 == 6) box.max().y() = nan;
        boxes.push_back({SlotAt(o), box});
        const bool no_triangles = o % 29 == 3;
        objects.push_back({vertices, no_triangles ? std::span<const TriangleIndices>() : triangle,
                           no_triangles ? std::span<const ComputeNode>() : leaf,
                           no_triangles ? std::span<const uint32_t>() : order,
                           static_cast<uint64_t>(o + 1), ++world_key_,
                           SweepAndPrune::GrownBox(box, margin)});
      }
      const std::vector<SlotPair> expected = SweepAndPrune().Update(boxes, margin);
      ComputeQuery query;
      query.objects = objects;
      auto collider = ComputeCollider::Create();  // its buffers as small as at first
      ASSERT_TRUE(collider.ok()) << ToString(collider.error());
      auto answer = (*collider)->Run(query);
      ASSERT_TRUE(answer.ok()) << ToString(answer.error());
      EXPECT_EQ(answer->object_pairs, expected) << num_objects << " objects, margin " << margin;
      // Every descended pair is one triangle against one: the same triangle, crossing itself
      // (coplanar: undecided), except for the objects without triangles.
      size_t descended = 0;
      for (const SlotPair& pair : expected)
        descended += Index(pair.object_a) % 29 != 3 && Index(pair.object_b) % 29 != 3 ? 1 : 0;
      EXPECT_EQ(static_cast<size_t>(answer->box_pairs), descended);
      if (num_objects == 2000) {
        EXPECT_GT(expected.size(), size_t{4096});
        EXPECT_GT(answer->runs, 1) << "the pair buffer should have grown";
      }
    }
  }
}

}  // namespace
}  // namespace far
