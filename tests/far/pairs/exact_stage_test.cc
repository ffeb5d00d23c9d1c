#include "far/pairs/exact_stage.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "pairs_of.h"
#include <gtest/gtest.h>

#include "far/base/assert.h"
#include "far/geometry/triangle_tests.h"

namespace far {
namespace {

using testing::PairsOf;

// Objects that own their vertices and triangles, and views of them: object o is slot o.
struct SoupScene {
  std::vector<std::vector<Eigen::Vector3d>> positions;
  std::vector<std::vector<TriangleIndices>> triangles;

  size_t size() const { return positions.size(); }
  std::vector<WorldObjectView> Views() const {
    std::vector<WorldObjectView> views;
    for (size_t o = 0; o < size(); ++o) views.push_back({positions[o], triangles[o]});
    return views;
  }

  TrianglePoints Corners(size_t object, uint32_t triangle) const {
    const TriangleIndices& v = triangles[object][triangle];
    return {positions[object][v[0]], positions[object][v[1]], positions[object][v[2]]};
  }

  // Every object pair by slot, a < b.
  std::vector<SlotPair> AllPairs() const {
    std::vector<SlotPair> pairs;
    for (size_t a = 0; a < size(); ++a) {
      for (size_t b = a + 1; b < size(); ++b) pairs.push_back({SlotAt(a), SlotAt(b)});
    }
    return pairs;
  }
};

// A query of `views` and `pairs`: with subsets when not empty, with distance pairs within D.
ExactQuery Query(std::span<const WorldObjectView> views, std::span<const SlotPair> pairs,
                 std::span<const std::vector<uint32_t>> subsets, std::optional<double> distance) {
  ExactQuery query;
  query.objects = views;
  query.object_pairs = pairs;
  query.triangle_subsets = subsets;
  query.max_distance = distance;
  return query;
}

// Random triangle soups. With `grid`, coordinates are multiples of 1/8 and a fifth of the corners
// of later objects are copied from earlier objects' corners or edge midpoints, so that shared
// vertices, vertex-on-edge, touching boxes and coplanar pairs are common; one triangle in ten is
// degenerate (a segment or a point).
SoupScene RandomSoup(uint32_t seed, int num_objects, int triangles_each, double extent, double size,
                     bool grid, double offset = 0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  const auto quantize = [&](double x) { return grid ? std::round(x * 8) / 8 : x; };
  const auto random_point = [&](const Eigen::Vector3d& center, double radius) {
    Eigen::Vector3d p;
    for (int axis = 0; axis < 3; ++axis)
      p[axis] = quantize(center[axis] + (2 * unit(rng) - 1) * radius);
    return p;
  };
  SoupScene scene;
  for (int o = 0; o < num_objects; ++o) {
    std::vector<Eigen::Vector3d> points;
    std::vector<TriangleIndices> triangles;
    for (int t = 0; t < triangles_each; ++t) {
      const Eigen::Vector3d center =
          random_point(Eigen::Vector3d::Constant(extent / 2), extent / 2);
      Eigen::Vector3d p[3];
      for (Eigen::Vector3d& corner : p) corner = random_point(center, size);
      // Borrow corners from earlier objects: exact touching.
      for (Eigen::Vector3d& corner : p) {
        if (!grid || o == 0 || unit(rng) >= 0.2) continue;
        const size_t other = static_cast<size_t>(unit(rng) * o);
        const std::vector<Eigen::Vector3d>& theirs = scene.positions[other];
        if (theirs.size() < 2) continue;
        const size_t i = static_cast<size_t>(unit(rng) * theirs.size());
        const size_t j = (i + 1) % theirs.size();
        corner = unit(rng) < 0.5 ? theirs[i] : Eigen::Vector3d((theirs[i] + theirs[j]) / 2);
      }
      const double kind = unit(rng);
      if (kind < 0.04) {
        p[1] = p[2] = p[0];  // a point
      } else if (kind < 0.07) {
        p[2] = p[0];  // a segment
      } else if (kind < 0.1) {
        p[2] = (p[0] + p[1]) / 2;  // collinear
      }
      const auto base = static_cast<uint32_t>(points.size());
      for (const Eigen::Vector3d& corner : p)
        points.push_back(corner + Eigen::Vector3d::Constant(offset));
      triangles.push_back({base, base + 1, base + 2});
    }
    scene.positions.push_back(std::move(points));
    scene.triangles.push_back(std::move(triangles));
  }
  return scene;
}

// The unfiltered O(n^2) loops: every cross-object triangle pair straight into the predicates.
std::vector<SlotContact> UnfilteredContacts(const SoupScene& scene) {
  std::vector<SlotContact> contacts;
  for (size_t i = 0; i < scene.size(); ++i) {
    for (size_t j = i + 1; j < scene.size(); ++j) {
      for (uint32_t a = 0; a < scene.triangles[i].size(); ++a) {
        for (uint32_t b = 0; b < scene.triangles[j].size(); ++b) {
          if (TrianglesIntersect(scene.Corners(i, a), scene.Corners(j, b))) {
            contacts.push_back({SlotAt(i), a, SlotAt(j), b});
          }
        }
      }
    }
  }
  std::sort(contacts.begin(), contacts.end());
  return contacts;
}

std::vector<SlotContact> UnfilteredWithin(const SoupScene& scene, double max_distance) {
  std::vector<SlotContact> pairs;
  for (size_t i = 0; i < scene.size(); ++i) {
    for (size_t j = i + 1; j < scene.size(); ++j) {
      for (uint32_t a = 0; a < scene.triangles[i].size(); ++a) {
        for (uint32_t b = 0; b < scene.triangles[j].size(); ++b) {
          if (TrianglesWithinDistance(scene.Corners(i, a), scene.Corners(j, b), max_distance)) {
            pairs.push_back({SlotAt(i), a, SlotAt(j), b});
          }
        }
      }
    }
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

// Sorted, unique, object_a < object_b, and every distance is TriangleDistance of the pair.
void ExpectWellFormed(const SoupScene& scene, const ExactResult& result) {
  for (const SlotContact& c : result.contacts) EXPECT_LT(c.object_a, c.object_b);
  for (size_t i = 1; i < result.contacts.size(); ++i) {
    EXPECT_LT(result.contacts[i - 1], result.contacts[i]);
  }
  for (size_t i = 1; i < result.distance_pairs.size(); ++i) {
    EXPECT_LT(result.distance_pairs[i - 1].pair, result.distance_pairs[i].pair);
  }
  for (const SlotDistancePair& d : result.distance_pairs) {
    EXPECT_LT(d.pair.object_a, d.pair.object_b);
    const double expected =
        TriangleDistance(scene.Corners(Index(d.pair.object_a), d.pair.triangle_a),
                         scene.Corners(Index(d.pair.object_b), d.pair.triangle_b));
    EXPECT_NEAR(d.distance, expected, 1e-12 * (1 + expected));
  }
  EXPECT_LE(result.pairs_tested, result.pairs_considered);
}

TEST(ExactStageTest, FullQueryMatchesBruteForce) {
  ThreadPool pool(2);
  for (uint32_t seed : {1u, 2u, 3u, 4u}) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    const SoupScene scene = RandomSoup(seed, 5, 60, 4.0, 0.6, seed % 2 == 0);
    const std::vector<WorldObjectView> views = scene.Views();
    const std::vector<SlotPair> pairs = scene.AllPairs();
    const ExactQuery query = Query(views, pairs, {}, 0.1);
    const ExactResult result = RunExactTests(query, pool);
    const ExactResult reference = BruteForceReference(views, 0.1, pool);
    ExpectWellFormed(scene, result);
    ExpectWellFormed(scene, reference);
    EXPECT_FALSE(reference.contacts.empty());
    EXPECT_EQ(result.contacts, reference.contacts);
    EXPECT_EQ(PairsOf(result.distance_pairs), PairsOf(reference.distance_pairs));
    EXPECT_GT(reference.distance_pairs.size(), reference.contacts.size());
    EXPECT_EQ(result.pairs_considered, reference.pairs_considered);
    EXPECT_EQ(reference.pairs_considered, 10u * 60 * 60);
    EXPECT_LE(result.pairs_tested, reference.pairs_tested);
  }
}

TEST(ExactStageTest, SubsetsMatchBruteForceRestrictedToThem) {
  ThreadPool pool(3);
  for (uint32_t seed : {11u, 12u, 13u}) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    const SoupScene scene = RandomSoup(seed, 6, 50, 4.0, 0.7, true);
    const std::vector<WorldObjectView> views = scene.Views();
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> percent(0, 99);
    // Random object pairs and random triangle subsets (one object gets an empty subset).
    std::vector<SlotPair> pairs;
    for (const SlotPair& pair : scene.AllPairs()) {
      if (percent(rng) < 70) pairs.push_back(pair);
    }
    std::vector<std::vector<uint32_t>> subsets(scene.size());
    for (size_t o = 1; o < scene.size(); ++o) {
      for (uint32_t t = 0; t < scene.triangles[o].size(); ++t) {
        if (percent(rng) < 60) subsets[o].push_back(t);
      }
      std::shuffle(subsets[o].begin(), subsets[o].end(), rng);
    }
    const ExactQuery query = Query(views, pairs, subsets, 0.2);
    const ExactResult result = RunExactTests(query, pool);
    ExpectWellFormed(scene, result);

    // The reference restricted to the query's object pairs and subsets.
    const auto in_query = [&](const SlotContact& c) {
      const auto in_subset = [&](ObjectSlot slot, uint32_t t) {
        const std::vector<uint32_t>& subset = subsets[Index(slot)];
        return std::find(subset.begin(), subset.end(), t) != subset.end();
      };
      return std::binary_search(pairs.begin(), pairs.end(), SlotPair{c.object_a, c.object_b}) &&
             in_subset(c.object_a, c.triangle_a) && in_subset(c.object_b, c.triangle_b);
    };
    const ExactResult reference = BruteForceReference(views, 0.2, pool);
    std::vector<SlotContact> expected_contacts;
    std::copy_if(reference.contacts.begin(), reference.contacts.end(),
                 std::back_inserter(expected_contacts), in_query);
    std::vector<SlotContact> expected_within;
    for (const SlotContact& c : PairsOf(reference.distance_pairs)) {
      if (in_query(c)) expected_within.push_back(c);
    }
    EXPECT_FALSE(expected_contacts.empty());
    EXPECT_EQ(result.contacts, expected_contacts);
    EXPECT_EQ(PairsOf(result.distance_pairs), expected_within);

    size_t considered = 0;
    for (const SlotPair& pair : pairs) {
      considered += subsets[Index(pair.object_a)].size() * subsets[Index(pair.object_b)].size();
    }
    EXPECT_EQ(result.pairs_considered, considered);
  }
}

TEST(ExactStageTest, PrefilterNeverDropsAnIntersectingPair) {
  ThreadPool pool(2);
  for (uint32_t seed = 21; seed < 29; ++seed) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    // Dense, small, on a grid: many touching and coplanar pairs.
    const SoupScene scene = RandomSoup(seed, 4, 40, 2.0, 0.5, true);
    const std::vector<WorldObjectView> views = scene.Views();
    const std::vector<SlotPair> pairs = scene.AllPairs();
    const std::vector<SlotContact> expected = UnfilteredContacts(scene);
    EXPECT_FALSE(expected.empty());
    const ExactResult result = RunExactTests(Query(views, pairs, {}, std::nullopt), pool);
    ExpectWellFormed(scene, result);
    EXPECT_EQ(result.contacts, expected);
    EXPECT_TRUE(result.distance_pairs.empty());
    EXPECT_LT(result.pairs_tested, result.pairs_considered);
    EXPECT_EQ(BruteForceReference(views, std::nullopt, pool).contacts, expected);
  }
}

TEST(ExactStageTest, TouchingAtOneCornerIsAContact) {
  // Two triangles that share a vertex and whose boxes share only boundary points.
  SoupScene scene;
  scene.positions = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{1, 0, 0}, {2, 1, 1}, {2, 0, 1}}};
  scene.triangles = {{{0, 1, 2}}, {{0, 1, 2}}};
  // And a point triangle lying on the first one's face, on its box's boundary plane z = 0.
  scene.positions.push_back({{0.25, 0.25, 0}});
  scene.triangles.push_back({{0, 0, 0}});
  const std::vector<WorldObjectView> views = scene.Views();
  ThreadPool pool(1);
  const std::vector<SlotPair> pairs = scene.AllPairs();
  const ExactResult result = RunExactTests(Query(views, pairs, {}, std::nullopt), pool);
  const ObjectSlot s0 = SlotAt(0), s1 = SlotAt(1), s2 = SlotAt(2);
  EXPECT_EQ(result.contacts, (std::vector<SlotContact>{{s0, 0, s1, 0}, {s0, 0, s2, 0}}));
  EXPECT_EQ(result.contacts, UnfilteredContacts(scene));
}

TEST(ExactStageTest, DistancePairsMatchUnfilteredLoop) {
  ThreadPool pool(2);
  for (uint32_t seed = 31; seed < 37; ++seed) {
    for (double max_distance : {0.0, 0.05, 0.3}) {
      SCOPED_TRACE(::testing::Message() << "seed " << seed << " D " << max_distance);
      const bool grid = seed % 2 == 1;
      const double offset = seed % 3 == 0 ? 1e5 : 0.0;  // far from the origin
      const SoupScene scene = RandomSoup(seed, 4, 30, 3.0, 0.4, grid, offset);
      const std::vector<WorldObjectView> views = scene.Views();
      const std::vector<SlotPair> pairs = scene.AllPairs();
      const std::vector<SlotContact> expected = UnfilteredWithin(scene, max_distance);
      const ExactResult result = RunExactTests(Query(views, pairs, {}, max_distance), pool);
      ExpectWellFormed(scene, result);
      EXPECT_EQ(result.contacts, UnfilteredContacts(scene));
      EXPECT_EQ(PairsOf(result.distance_pairs), expected);
      EXPECT_EQ(PairsOf(BruteForceReference(views, max_distance, pool).distance_pairs), expected);
      for (const SlotDistancePair& d : result.distance_pairs)
        EXPECT_LE(d.distance, max_distance + 1e-9);
    }
  }
}

TEST(ExactStageTest, DistancePrefilterIsNoStricterThanThePredicate) {
  // Parallel triangles just beyond D along x: TrianglesWithinDistance may accept some of them
  // (its documented slack), so the box prefilter must let them all through to it.
  ThreadPool pool(2);
  for (double offset : {0.0, 1e3, 1e5}) {
    for (double max_distance : {0.0, 0.1}) {
      SCOPED_TRACE(::testing::Message() << "offset " << offset << " D " << max_distance);
      SoupScene scene;
      scene.positions = {{{offset, 0, 0}, {offset, 1, 0}, {offset, 0, 1}}, {}};
      scene.triangles = {{{0, 1, 2}}, {}};
      double x = offset + max_distance;
      for (uint32_t k = 0; k < 64; ++k) {
        scene.positions[1].push_back({x, 0, 0});
        scene.positions[1].push_back({x, 1, 0});
        scene.positions[1].push_back({x, 0, 1});
        scene.triangles[1].push_back({3 * k, 3 * k + 1, 3 * k + 2});
        x = std::nextafter(x, 1e300);
      }
      const std::vector<WorldObjectView> views = scene.Views();
      const std::vector<SlotContact> expected = UnfilteredWithin(scene, max_distance);
      // Near the origin the predicate's slack spans several ulps; far away, less than one.
      if (offset == 0) {
        EXPECT_GT(expected.size(), 1u);
      }
      const std::vector<SlotPair> pairs = scene.AllPairs();
      const ExactResult result = RunExactTests(Query(views, pairs, {}, max_distance), pool);
      EXPECT_EQ(PairsOf(result.distance_pairs), expected);
      EXPECT_EQ(PairsOf(BruteForceReference(views, max_distance, pool).distance_pairs), expected);
    }
  }
}

TEST(ExactStageTest, ThreadCountsGiveIdenticalOutput) {
  // Two big objects (many work items each) and several small ones.
  SoupScene scene = RandomSoup(41, 2, 3000, 10.0, 0.4, false);
  const SoupScene small = RandomSoup(42, 6, 40, 10.0, 1.0, true);
  for (size_t o = 0; o < small.size(); ++o) {
    scene.positions.push_back(small.positions[o]);
    scene.triangles.push_back(small.triangles[o]);
  }
  const std::vector<WorldObjectView> views = scene.Views();
  const std::vector<SlotPair> pairs = scene.AllPairs();
  ThreadPool one(1), four(4);
  const ExactQuery query = Query(views, pairs, {}, 0.05);
  const ExactResult a = RunExactTests(query, one);
  const ExactResult b = RunExactTests(query, four);
  ExpectWellFormed(scene, a);
  EXPECT_FALSE(a.contacts.empty());
  EXPECT_EQ(a.contacts, b.contacts);
  ASSERT_EQ(a.distance_pairs.size(), b.distance_pairs.size());
  for (size_t i = 0; i < a.distance_pairs.size(); ++i) {
    EXPECT_EQ(a.distance_pairs[i].pair, b.distance_pairs[i].pair);
    EXPECT_EQ(a.distance_pairs[i].distance, b.distance_pairs[i].distance);
  }
  EXPECT_EQ(a.pairs_considered, b.pairs_considered);
  EXPECT_EQ(a.pairs_tested, b.pairs_tested);
  // The sweep tests far fewer pairs than all, and finds what the brute force finds.
  EXPECT_LT(a.pairs_tested * 20, a.pairs_considered);
  const ExactResult reference = BruteForceReference(views, 0.05, four);
  EXPECT_EQ(a.contacts, reference.contacts);
  EXPECT_EQ(PairsOf(a.distance_pairs), PairsOf(reference.distance_pairs));
  EXPECT_EQ(a.pairs_considered, reference.pairs_considered);
}

TEST(ExactStageTest, ObjectsWithoutTrianglesGiveNothing) {
  SoupScene scene = RandomSoup(51, 3, 20, 1.0, 0.5, true);
  scene.positions.emplace_back();  // slot 3: no triangles
  scene.triangles.emplace_back();
  const std::vector<WorldObjectView> views = scene.Views();
  ThreadPool pool(2);
  const std::vector<SlotPair> pairs = {{SlotAt(0), SlotAt(3)}, {SlotAt(2), SlotAt(3)}};
  const ExactResult result = RunExactTests(Query(views, pairs, {}, 1.0), pool);
  EXPECT_TRUE(result.contacts.empty());
  EXPECT_TRUE(result.distance_pairs.empty());
  EXPECT_EQ(result.pairs_considered, 0u);
  EXPECT_EQ(result.pairs_tested, 0u);

  // Empty subsets likewise, and no pairs at all.
  const std::vector<std::vector<uint32_t>> empty_subsets(views.size());
  const std::vector<SlotPair> all_pairs = scene.AllPairs();
  const ExactResult subset_result =
      RunExactTests(Query(views, all_pairs, empty_subsets, 1.0), pool);
  EXPECT_TRUE(subset_result.contacts.empty());
  EXPECT_EQ(subset_result.pairs_considered, 0u);
  const ExactResult no_pairs = RunExactTests(Query(views, {}, {}, 1.0), pool);
  EXPECT_TRUE(no_pairs.contacts.empty());
  EXPECT_EQ(no_pairs.pairs_considered, 0u);
  EXPECT_TRUE(BruteForceReference({}, 1.0, pool).contacts.empty());

  // The reference skips the empty object and still finds the others' contacts.
  EXPECT_EQ(BruteForceReference(views, std::nullopt, pool).contacts, UnfilteredContacts(scene));
}

TEST(ExactStageTest, OnlyTheAskedOutputsAreComputed) {
  const SoupScene scene = RandomSoup(61, 3, 40, 2.0, 0.5, true);
  const std::vector<WorldObjectView> views = scene.Views();
  const std::vector<SlotPair> pairs = scene.AllPairs();
  ThreadPool pool(2);
  const ExactResult contacts_only = RunExactTests(Query(views, pairs, {}, std::nullopt), pool);
  EXPECT_FALSE(contacts_only.contacts.empty());
  EXPECT_TRUE(contacts_only.distance_pairs.empty());
  const ExactResult both = RunExactTests(Query(views, pairs, {}, 0.1), pool);
  EXPECT_EQ(both.contacts, contacts_only.contacts);
  // Every contact is a distance pair at distance 0.
  for (const SlotContact& c : both.contacts) {
    const auto it = std::lower_bound(both.distance_pairs.begin(), both.distance_pairs.end(),
                                     SlotDistancePair{c, 0});
    ASSERT_NE(it, both.distance_pairs.end());
    EXPECT_EQ(it->pair, c);
    EXPECT_EQ(it->distance, 0.0);
  }
  // A distance that only widens the search (want_distance_pairs false) reports no distance
  // pairs, and the same contacts.
  ExactQuery widened = Query(views, pairs, {}, 0.1);
  widened.want_distance_pairs = false;
  const ExactResult wide = RunExactTests(widened, pool);
  EXPECT_EQ(wide.contacts, contacts_only.contacts);
  EXPECT_TRUE(wide.distance_pairs.empty());
}

TEST(ExactStageTest, APairOfSlotsOutsideTheObjectsIsRefusedBeforeAnyRead) {
  // FAR_DEMAND: a slot past the query's objects would read out of bounds in every build. The
  // test's handler throws instead of aborting (far/base/assert.h).
  const internal::AssertionHandler previous =
      internal::SetAssertionHandler([](const internal::AssertionFailure& failure) {
        throw std::logic_error(std::string(failure.message));
      });
  const SoupScene scene = RandomSoup(71, 2, 10, 1.0, 0.5, true);
  const std::vector<WorldObjectView> views = scene.Views();
  const std::vector<SlotPair> pairs = {{SlotAt(0), SlotAt(2)}};
  ThreadPool pool(1);
  EXPECT_THROW((void)RunExactTests(Query(views, pairs, {}, std::nullopt), pool), std::logic_error);
  internal::SetAssertionHandler(previous);
}

}  // namespace
}  // namespace far
