// TriangleBvh and the hierarchy stage (RunBvhTests) against the brute-force reference: random
// meshes under random poses, shared corners and touching triangles, far from the origin, tiny
// features, distance queries, deformation (refit) and thread counts.
#include "far/pairs/bvh_stage.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include "pairs_of.h"
#include <gtest/gtest.h>

#include "far/pairs/triangle_bvh.h"

namespace far {
namespace {

using testing::PairsOf;

// One object: mesh in its frame M, pose, world vertices and hierarchy. Object o of a scene is
// slot o.
struct Object {
  std::vector<Eigen::Vector3d> p_MV;
  std::vector<TriangleIndices> triangles;
  Eigen::Isometry3d X_WM = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Vector3d> p_WV;
  TriangleBvh bvh;

  void Place() {
    p_WV.clear();
    for (const auto& p : p_MV) p_WV.push_back(WorldVertex(X_WM, p));  // as the pipeline
  }
  WorldObjectView View() const { return {p_WV, triangles}; }
};

Eigen::Isometry3d RandomPose(std::mt19937& rng, double extent, double offset) {
  std::uniform_real_distribution<double> unit(-1, 1);
  Eigen::Quaterniond q(unit(rng), unit(rng), unit(rng), unit(rng));
  q.normalize();
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = q.toRotationMatrix();
  X.translation() =
      Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * extent + Eigen::Vector3d::Constant(offset);
  return X;
}

// A blob of `n` random triangles of size about `size` in a ball of radius `radius` in frame M,
// a tenth of them degenerate.
void RandomMesh(std::mt19937& rng, int n, double radius, double size, Object& object) {
  std::uniform_real_distribution<double> unit(-1, 1);
  for (int t = 0; t < n; ++t) {
    const Eigen::Vector3d c = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * radius;
    const auto base = static_cast<uint32_t>(object.p_MV.size());
    for (int k = 0; k < 3; ++k)
      object.p_MV.push_back(c + Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * size);
    if (t % 10 == 0) object.p_MV.back() = object.p_MV[base];  // a segment
    object.triangles.push_back({base, base + 1, base + 2});
  }
}

std::vector<Object> RandomScene(uint32_t seed, int objects, int triangles, double offset,
                                double scale = 1.0) {
  std::mt19937 rng(seed);
  std::vector<Object> scene(static_cast<size_t>(objects));
  for (int o = 0; o < objects; ++o) {
    Object& object = scene[static_cast<size_t>(o)];
    RandomMesh(rng, triangles, 0.6 * scale, 0.15 * scale, object);
    object.X_WM = RandomPose(rng, 0.4 * scale, offset);
    object.Place();
    object.bvh.Build(object.p_MV, object.triangles);
  }
  return scene;
}

std::vector<WorldObjectView> Views(const std::vector<Object>& scene) {
  std::vector<WorldObjectView> views;
  for (const Object& o : scene) views.push_back(o.View());
  return views;
}

std::vector<ObjectHierarchy> Hierarchies(const std::vector<Object>& scene) {
  std::vector<ObjectHierarchy> hierarchies;
  for (const Object& o : scene) hierarchies.push_back({&o.bvh, o.X_WM});
  return hierarchies;
}

std::vector<SlotPair> AllPairs(const std::vector<Object>& scene) {
  std::vector<SlotPair> pairs;
  for (size_t a = 0; a < scene.size(); ++a)
    for (size_t b = a + 1; b < scene.size(); ++b) pairs.push_back({SlotAt(a), SlotAt(b)});
  return pairs;
}

ExactResult ReferenceResult(const std::vector<Object>& scene, std::optional<double> distance) {
  ThreadPool pool(2);
  return BruteForceReference(Views(scene), distance, pool);
}

BvhResult RunStage(const std::vector<Object>& scene, std::optional<double> distance,
                   int threads = 2) {
  const std::vector<WorldObjectView> views = Views(scene);
  const std::vector<ObjectHierarchy> hierarchies = Hierarchies(scene);
  const std::vector<SlotPair> pairs = AllPairs(scene);
  BvhQuery query;
  query.objects = views;
  query.object_pairs = pairs;
  query.max_distance = distance;
  query.hierarchies = hierarchies;
  ThreadPool pool(threads);
  return RunBvhTests(query, pool);
}

// Every leaf box holds its triangles and every inner box its children; each triangle once.
void ExpectValidTree(const Object& object) {
  const auto& nodes = object.bvh.nodes();
  ASSERT_FALSE(nodes.empty());
  std::vector<int> seen(object.triangles.size(), 0);
  // |p - center| <= half_extent holds exactly; evaluated in double it may be off by an ulp.
  auto inside = [](const TriangleBvh::Node& n, const Eigen::Vector3d& p) {
    const double ulps = 1e-15 * (n.center.cwiseAbs().maxCoeff() + n.half_extent.maxCoeff());
    return ((p - n.center).cwiseAbs() - n.half_extent).maxCoeff() <= ulps;
  };
  for (const auto& node : nodes) {
    if (node.leaf()) {
      EXPECT_LE(node.count, static_cast<uint32_t>(TriangleBvh::kLeafSize));
      for (uint32_t i = node.first; i < node.first + node.count; ++i) {
        const uint32_t t = object.bvh.order()[i];
        seen[t]++;
        for (uint32_t v : object.triangles[t]) EXPECT_TRUE(inside(node, object.p_MV[v]));
      }
    } else {
      for (uint32_t child : {node.first, node.first + 1}) {
        const auto& c = nodes[child];
        EXPECT_TRUE(inside(node, c.center - c.half_extent));
        EXPECT_TRUE(inside(node, c.center + c.half_extent));
      }
    }
  }
  for (int count : seen) EXPECT_EQ(count, 1);
}

TEST(TriangleBvhTest, EveryTriangleOnceInsideItsLeafAndAncestors) {
  for (int n : {1, 3, 4, 5, 17, 1000}) {
    std::vector<Object> scene = RandomScene(static_cast<uint32_t>(n), 1, n, 0);
    ExpectValidTree(scene[0]);
  }
}

TEST(TriangleBvhTest, IdenticalTrianglesStillSplit) {
  Object object;
  for (int t = 0; t < 100; ++t) {
    const auto base = static_cast<uint32_t>(object.p_MV.size());
    object.p_MV.insert(object.p_MV.end(), {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    object.triangles.push_back({base, base + 1, base + 2});
  }
  object.bvh.Build(object.p_MV, object.triangles);
  ExpectValidTree(object);
}

TEST(TriangleBvhTest, RefitFollowsMovedVerticesAndRebuildsWhenLoose) {
  std::vector<Object> scene = RandomScene(5, 1, 500, 0);
  Object& object = scene[0];
  // A small wiggle keeps the tree; a scramble makes it loose and rebuilds it.
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (auto& p : object.p_MV) p += Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * 1e-3;
  EXPECT_FALSE(object.bvh.Refit(object.p_MV, object.triangles));
  ExpectValidTree(object);
  for (auto& p : object.p_MV) p = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * 5;
  EXPECT_TRUE(object.bvh.Refit(object.p_MV, object.triangles));
  ExpectValidTree(object);
}

TEST(TriangleBvhTest, SlabsHoldTheirTrianglesAndRefitDropsThem) {
  std::vector<Object> scene = RandomScene(12, 1, 400, 0);
  Object& object = scene[0];
  const auto& slabs = object.bvh.slabs();
  ASSERT_EQ(slabs.size(), object.triangles.size());
  // The slabs are relative to the center of each triangle's leaf.
  std::vector<Eigen::Vector3d> leaf_center(slabs.size());
  for (const TriangleBvh::Node& node : object.bvh.nodes()) {
    for (uint32_t k = node.first; k < node.first + node.count; ++k) leaf_center[k] = node.center;
  }
  int degenerate = 0;
  for (size_t k = 0; k < slabs.size(); ++k) {
    const TriangleBvh::Slab& slab = slabs[k];
    const TriangleIndices& t = object.triangles[object.bvh.order()[k]];
    if (slab.axis[0].isZero()) {
      // Only a triangle with no plane has no slabs (RandomMesh makes every tenth a segment).
      EXPECT_TRUE((object.p_MV[t[1]] - object.p_MV[t[0]])
                      .cross(object.p_MV[t[2]] - object.p_MV[t[0]])
                      .isZero());
      ++degenerate;
      continue;
    }
    // Float axes, just shorter than 1 (never longer), and perpendicular up to float rounding.
    for (int axis = 0; axis < TriangleBvh::Slab::kAxes; ++axis) {
      EXPECT_LE(slab.Axis(axis).norm(), 1.0);
      EXPECT_NEAR(slab.Axis(axis).norm(), 1.0, 1e-6);
    }
    EXPECT_NEAR(slab.Axis(0).dot(slab.Axis(1)), 0.0, 1e-6);
    for (uint32_t v : t) {
      for (int axis = 0; axis < TriangleBvh::Slab::kAxes; ++axis) {
        const double along = slab.Axis(axis).dot(object.p_MV[v] - leaf_center[k]);
        EXPECT_GE(along, slab.lo[axis] - 1e-15);
        EXPECT_LE(along, slab.hi[axis] + 1e-15);
      }
    }
    // The first slab is the triangle's plane: as thin as rounding outward to float leaves it (a
    // few float steps, 2^-23 each, of the distance to the leaf's center; well under 1e-6 here). The
    // second is as wide as the triangle's height over its longest edge: 2 area / longest edge.
    EXPECT_LE(slab.hi[0] - slab.lo[0], 1e-6);
    const Eigen::Vector3d a = object.p_MV[t[0]], b = object.p_MV[t[1]], c = object.p_MV[t[2]];
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    EXPECT_NEAR(slab.hi[1] - slab.lo[1], (b - a).cross(c - a).norm() / longest, 1e-6);
  }
  EXPECT_EQ(degenerate, 40);
  // A refit (a deformable object's step) keeps no slabs: computing them would cost as much as
  // the refit itself; a rebuild makes them anew.
  for (auto& p : object.p_MV) p *= 1.001;
  ASSERT_FALSE(object.bvh.Refit(object.p_MV, object.triangles));
  EXPECT_TRUE(object.bvh.slabs().empty());
  object.bvh.Build(object.p_MV, object.triangles);
  EXPECT_EQ(object.bvh.slabs().size(), object.triangles.size());
  // Rebuilt with no triangles (every one removed), it keeps none of the old slabs.
  object.bvh.Build(object.p_MV, {});
  EXPECT_TRUE(object.bvh.empty());
  EXPECT_TRUE(object.bvh.slabs().empty());
}

// The slabs' float bounds are relative to their leaf: a mesh millions of units from its frame's
// origin (a static object given in world coordinates far out) keeps slabs as thin as at the
// origin. Absolute float bounds (bounds relative to the origin, tried) made the thickest plane
// 0.25 units here, the spacing of floats near 3e6.
TEST(TriangleBvhTest, SlabsStayThinFarFromTheOrigin) {
  std::vector<Object> scene = RandomScene(13, 1, 300, 0);
  Object& object = scene[0];
  for (auto& p : object.p_MV) p += Eigen::Vector3d(1e6, -2e6, 3e6);
  object.bvh.Build(object.p_MV, object.triangles);
  double thickest_plane = 0;
  for (const TriangleBvh::Slab& slab : object.bvh.slabs()) {
    if (!slab.axis[0].isZero())
      thickest_plane = std::max<double>(thickest_plane, slab.hi[0] - slab.lo[0]);
  }
  EXPECT_GT(thickest_plane, 0);
  EXPECT_LE(thickest_plane, 1e-6);
}

TEST(BvhStageTest, ContactsMatchTheReferenceUnderRandomPoses) {
  for (uint32_t seed = 1; seed <= 12; ++seed) {
    SCOPED_TRACE(seed);
    const std::vector<Object> scene = RandomScene(seed, 6, 150, 0);
    const ExactResult expected = ReferenceResult(scene, std::nullopt);
    const BvhResult got = RunStage(scene, std::nullopt);
    EXPECT_EQ(got.exact.contacts, expected.contacts);
    // Every contact's triangles are candidates.
    for (const SlotContact& c : expected.contacts) {
      for (const auto& [slot, t] :
           {std::pair{c.object_a, c.triangle_a}, {c.object_b, c.triangle_b}}) {
        const size_t o = Index(slot);
        EXPECT_TRUE(std::binary_search(got.candidates[o].begin(), got.candidates[o].end(), t));
      }
    }
    EXPECT_GT(expected.contacts.size(), 0u) << "the scenes must have contacts";
  }
}

TEST(BvhStageTest, FarFromTheOriginAndAtTinyScales) {
  for (const auto& [offset, scale] : {std::pair{1e5, 1.0}, {1e6, 1e-3}, {-3e4, 1e-5}}) {
    SCOPED_TRACE(offset);
    const std::vector<Object> scene = RandomScene(31, 5, 120, offset, scale);
    const ExactResult expected = ReferenceResult(scene, std::nullopt);
    EXPECT_EQ(RunStage(scene, std::nullopt).exact.contacts, expected.contacts);
    EXPECT_GT(expected.contacts.size(), 0u);
  }
}

// World coordinates below kTinyWorldCoordinate are 0, as the pipeline places objects: around it
// some corners move onto others, below it every corner is the origin and every pair touches. The
// descent runs on the meshes in their own frames, unflushed: its margin must cover the flush
// (without it, the bvh_reference fuzz target found a missed contact within a minute).
TEST(BvhStageTest, AroundAndBelowTheTinyWorldCoordinate) {
  for (const double scale : {0x1p-250, 0x1p-254, 0x1p-262}) {
    SCOPED_TRACE(scale);
    const std::vector<Object> scene = RandomScene(37, 4, 60, 0, scale);
    const ExactResult expected = ReferenceResult(scene, std::nullopt);
    EXPECT_EQ(RunStage(scene, std::nullopt).exact.contacts, expected.contacts);
    EXPECT_GT(expected.contacts.size(), 0u);
  }
}

TEST(BvhStageTest, TouchingAtACornerUnderARotatedPose) {
  // Two triangles that share exactly one world corner; B's mesh is given in a rotated frame.
  Object a, b;
  a.p_MV = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  a.triangles = {{0, 1, 2}};
  b.X_WM = Eigen::Isometry3d::Identity();
  b.X_WM.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  b.X_WM.translation() = Eigen::Vector3d(1, 0, 0);
  // Pick B's corner so that it lands exactly on A's corner (1, 0, 0): the origin of M.
  b.p_MV = {{0, 0, 0}, {0, 0, 1}, {0, -1, 1}};
  b.triangles = {{0, 1, 2}};
  for (Object* o : {&a, &b}) {
    o->Place();
    o->bvh.Build(o->p_MV, o->triangles);
  }
  const std::vector<Object> scene = {a, b};
  const ExactResult expected = ReferenceResult(scene, std::nullopt);
  ASSERT_EQ(expected.contacts.size(), 1u);
  const BvhResult found = RunStage(scene, std::nullopt);
  EXPECT_EQ(found.exact.contacts, expected.contacts);
  // Each hierarchy is one leaf: one leaf sent down a one-node hierarchy, one leaf pair, one
  // triangle pair whose boxes meet (at the corner), no inner node pair.
  const DescentCounters& c = found.counters;
  EXPECT_EQ(c.node_pairs, 0);
  EXPECT_EQ(c.leaf_descents, 1);
  EXPECT_EQ(c.leaf_descent_nodes, 1);
  EXPECT_EQ(c.leaf_pairs, 1);
  EXPECT_EQ(c.boxes_met, 1);
}

TEST(BvhStageTest, CountersFollowTheDescent) {
  // Each step of the descent narrows the one before: nodes visited, leaf pairs, triangle pairs
  // whose boxes meet, exact tests.
  const std::vector<Object> scene = RandomScene(12, 6, 400, 0);
  const BvhResult found = RunStage(scene, std::nullopt);
  const DescentCounters& c = found.counters;
  ASSERT_FALSE(found.exact.contacts.empty());
  EXPECT_GT(c.node_pairs, 0);
  EXPECT_GT(c.leaf_descents, 0);
  EXPECT_LE(c.leaf_descents, c.leaf_descent_nodes);
  EXPECT_LE(c.leaf_pairs, c.leaf_descent_nodes);
  EXPECT_LT(c.boxes_met, static_cast<int64_t>(found.exact.pairs_considered));
  EXPECT_LE(static_cast<int64_t>(found.exact.pairs_tested), c.boxes_met);
  EXPECT_GT(found.exact.pairs_tested, 0u);
  // Objects far apart: no root pair overlaps, nothing is counted.
  std::vector<Object> apart = RandomScene(12, 2, 50, 0);
  apart[1].X_WM.translation() += Eigen::Vector3d(100, 0, 0);
  apart[1].Place();
  EXPECT_EQ(RunStage(apart, std::nullopt).counters, DescentCounters{});
}

// Object A: `triangles` random triangles placed near `offset`; object B: no triangles yet, under
// another random pose there. The tests below give B triangles made in the world from A's and
// mapped into B's own frame through X_BW (B's pose inverted), so that they land on A's only up
// to the rounding of the two poses.
void MakeMirrorPair(std::mt19937& rng, int triangles, double offset, Object& a, Object& b) {
  RandomMesh(rng, triangles, 1.0, 0.2, a);
  a.X_WM = RandomPose(rng, 0.1, offset);
  a.Place();
  b.X_WM = RandomPose(rng, 0.1, offset);
}

// Appends the world triangle (p, q, r) to B, mapped into B's frame.
void AddWorldTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r,
                      Object& b) {
  const Eigen::Isometry3d X_BW = b.X_WM.inverse();
  const auto base = static_cast<uint32_t>(b.p_MV.size());
  for (const Eigen::Vector3d& p_W : {p, q, r}) b.p_MV.push_back(X_BW * p_W);
  b.triangles.push_back({base, base + 1, base + 2});
}

// Places and builds both objects; the hierarchy stage must find the reference's contacts, of
// which there must be more than `min_contacts`.
void ExpectTheReferenceContacts(Object& a, Object& b, size_t min_contacts) {
  for (Object* o : {&a, &b}) {
    o->Place();
    o->bvh.Build(o->p_MV, o->triangles);
  }
  const std::vector<Object> scene = {a, b};
  const ExactResult expected = ReferenceResult(scene, std::nullopt);
  EXPECT_GT(expected.contacts.size(), min_contacts);
  EXPECT_EQ(RunStage(scene, std::nullopt).exact.contacts, expected.contacts);
}

// Triangles of B that share a corner (or a point of an edge) with a triangle of A in the world:
// B's mesh is that world geometry mapped into B's own rotated frame far from the origin, so its
// world vertices, computed back through X_WB, land on A's only up to rounding. Whether each pair
// still touches is for the exact predicates to say on the rounded coordinates; the hierarchy
// must hand every such pair to them (its margin covers the rounding of the transforms).
TEST(BvhStageTest, CornersSharedThroughRoundedPosesFarFromTheOrigin) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (const auto& [offset, same_rotation] :
       {std::pair{0.0, false}, {1e5, false}, {1e7, false}, {1e5, true}, {1e7, true}}) {
    SCOPED_TRACE(offset);
    SCOPED_TRACE(same_rotation);
    Object a, b;
    MakeMirrorPair(rng, 300, offset, a, b);
    // The same rotation takes the hierarchy stage's translation-only path.
    if (same_rotation) b.X_WM.linear() = a.X_WM.linear();
    for (uint32_t t = 0; t < a.triangles.size(); ++t) {
      const Eigen::Vector3d corner = a.p_WV[a.triangles[t][t % 3]];
      const Eigen::Vector3d edge_point =
          0.5 * (a.p_WV[a.triangles[t][0]] + a.p_WV[a.triangles[t][1]]);
      const Eigen::Vector3d touch = t % 2 ? corner : edge_point;
      const Eigen::Vector3d d1(unit(rng), unit(rng), unit(rng)),
          d2(unit(rng), unit(rng), unit(rng));
      AddWorldTriangle(touch, touch + 0.1 * d1, touch + 0.1 * d2, b);
    }
    ExpectTheReferenceContacts(a, b, 100);
  }
}

TEST(BvhStageTest, DistancePairsMatchTheReference) {
  for (double d : {0.0, 0.01, 0.2}) {
    SCOPED_TRACE(d);
    const std::vector<Object> scene = RandomScene(44, 5, 100, 0);
    const ExactResult expected = ReferenceResult(scene, d);
    const BvhResult got = RunStage(scene, d);
    EXPECT_EQ(PairsOf(got.exact.distance_pairs), PairsOf(expected.distance_pairs));
    EXPECT_EQ(got.exact.contacts, expected.contacts);
  }
}

TEST(BvhStageTest, RefitObjectsStayExact) {
  std::vector<Object> scene = RandomScene(71, 4, 200, 0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (int step = 0; step < 5; ++step) {
    for (Object& o : scene) {
      // Vertices move by more than the object's size over the steps.
      const Eigen::Vector3d drift = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * 0.3;
      for (auto& p : o.p_MV) p += drift + Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * 0.05;
      o.Place();
      (void)o.bvh.Refit(o.p_MV, o.triangles);
    }
    EXPECT_EQ(RunStage(scene, std::nullopt).exact.contacts,
              ReferenceResult(scene, std::nullopt).contacts);
  }
}

// A closed fan of slivers: a wavy loop of `n` points around the z axis, each edge joined to an
// apex off the loop's plane (the shape a fracture's fan closes a fragment with): long, thin,
// slanted triangles whose boxes are loose, so that a descent leans on their slabs.
void Fan(int n, double radius, const Eigen::Vector3d& apex, Object& object) {
  const auto base = static_cast<uint32_t>(object.p_MV.size());
  for (int i = 0; i < n; ++i) {
    const double angle = 2 * M_PI * i / n;
    object.p_MV.emplace_back(radius * std::cos(angle), radius * std::sin(angle),
                             0.1 * radius * std::sin(7 * angle));
  }
  object.p_MV.push_back(apex);
  for (uint32_t i = 0; i < static_cast<uint32_t>(n); ++i) {
    object.triangles.push_back(
        {base + i, base + (i + 1) % static_cast<uint32_t>(n), base + static_cast<uint32_t>(n)});
  }
}

// Fans of slivers crossing each other under random poses, near and far from the origin: the
// hierarchy with slabs (built) answers as the reference does, and as the same hierarchy without
// slabs (refit in place) does, having handed far fewer triangle pairs to the exact tests.
TEST(BvhStageTest, SliverFansMatchTheReferenceAndTheirSlabsPrune) {
  std::mt19937 rng(23);
  for (const double offset : {0.0, 1e5}) {
    SCOPED_TRACE(offset);
    std::vector<Object> scene(4);
    for (uint32_t o = 0; o < scene.size(); ++o) {
      Fan(200, 1.0, Eigen::Vector3d(0.2, -0.1, 0.6), scene[o]);
      Fan(150, 0.7, Eigen::Vector3d(-0.1, 0.2, -0.5), scene[o]);
      scene[o].X_WM = RandomPose(rng, 0.3, offset);
      scene[o].Place();
      scene[o].bvh.Build(scene[o].p_MV, scene[o].triangles);
    }
    for (const std::optional<double> distance : {std::optional<double>(), {0.02}}) {
      const ExactResult expected = ReferenceResult(scene, distance);
      const BvhResult with_slabs = RunStage(scene, distance);
      EXPECT_EQ(with_slabs.exact.contacts, expected.contacts);
      EXPECT_EQ(PairsOf(with_slabs.exact.distance_pairs), PairsOf(expected.distance_pairs));
      EXPECT_GT(expected.contacts.size(), 50u);

      std::vector<Object> plain = scene;
      for (Object& o : plain) {
        ASSERT_FALSE(o.bvh.Refit(o.p_MV, o.triangles));
        ASSERT_TRUE(o.bvh.slabs().empty());
      }
      const BvhResult without_slabs = RunStage(plain, distance);
      EXPECT_EQ(without_slabs.exact.contacts, expected.contacts);
      // The slabs cut the candidate pairs to about a third here (measured: 0.34-0.38). Tested
      // pair by pair as well, they leave a fifth of the exact tests (0.18-0.22; 0.61-0.64
      // when only the descent used them).
      EXPECT_LT(2 * with_slabs.exact.pairs_considered, without_slabs.exact.pairs_considered);
      EXPECT_LT(3 * with_slabs.exact.pairs_tested, without_slabs.exact.pairs_tested);
    }
  }
}

// Triangles of B lying in the planes of A's triangles, overlapping them (coplanar contact) or
// just short of their edges: B's mesh is that world geometry mapped into B's own rotated frame,
// far from the origin, so that every B triangle sits exactly on an A triangle's slab boundary
// up to the rounding of the poses. The slabs' margin must hand all of them to the predicates.
TEST(BvhStageTest, CoplanarTrianglesOnTheirSlabsThroughRoundedPoses) {
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> unit(0, 1);
  for (const double offset : {0.0, 1e4, 1e6}) {
    SCOPED_TRACE(offset);
    Object a, b;
    MakeMirrorPair(rng, 200, offset, a, b);
    for (const TriangleIndices& t : a.triangles) {
      const Eigen::Vector3d p = a.p_WV[t[0]], q = a.p_WV[t[1]], r = a.p_WV[t[2]];
      // Slid within A's plane along an edge: overlapping for s < 1, apart beyond.
      const Eigen::Vector3d shift = (0.5 + unit(rng)) * (q - p);
      AddWorldTriangle(p + shift, q + shift, r + shift, b);
    }
    ExpectTheReferenceContacts(a, b, 20);  // 42-48 of the 200 slid triangles touch
  }
}

TEST(BvhStageTest, ThreadCountsGiveIdenticalOutput) {
  const std::vector<Object> scene = RandomScene(8, 8, 300, 0);
  const BvhResult one = RunStage(scene, 0.05, 1);
  for (int threads : {2, 3, 8}) {
    const BvhResult many = RunStage(scene, 0.05, threads);
    EXPECT_EQ(many.exact.contacts, one.exact.contacts);
    EXPECT_EQ(PairsOf(many.exact.distance_pairs), PairsOf(one.exact.distance_pairs));
    EXPECT_EQ(many.candidates, one.candidates);
    EXPECT_EQ(many.exact.pairs_tested, one.exact.pairs_tested);
    EXPECT_EQ(many.counters, one.counters);
  }
}

}  // namespace
}  // namespace far
