#include "far/pairs/internal/pair_sort.h"

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace far::internal {
namespace {

// Pairs with fields drawn below the given bounds (1 << 32 and beyond: any uint32_t), with many
// equal fields so that every pass and the ties between fields matter.
std::vector<SlotContact> RandomPairs(size_t n, uint64_t object_bound, uint64_t triangle_bound,
                                     uint32_t seed) {
  std::mt19937_64 rng(seed);
  const auto below = [&](uint64_t bound) { return static_cast<uint32_t>(rng() % bound); };
  std::vector<SlotContact> pairs(n);
  for (SlotContact& p : pairs) {
    p = {SlotAt(below(object_bound)), below(triangle_bound), SlotAt(below(object_bound)),
         below(triangle_bound)};
  }
  return pairs;
}

TEST(PairSortTest, ContactsComeOutInPairOrder) {
  struct Case {
    size_t n;
    uint64_t objects, triangles;
  };
  // Sizes on both sides of the comparison-sort cutoff; small ids (the four fields packed in one
  // key: few passes), fields that fill exactly 64 bits (still packed, also with the slots'
  // fields always 0) and one bit more (sorted field by field), ids with their top bits set, and
  // fields that never vary (no pass). Slots are small in practice; the sort is right for any
  // uint32_t.
  const Case cases[] = {{0, 4, 10},
                        {1, 4, 10},
                        {5, 4, 10},
                        {127, 13, 100000},
                        {128, 13, 100000},
                        {129, 13, 100000},
                        {1500, 13, 100000},
                        {5000, 3, 300},
                        {5000, 1, 1},
                        {3000, 1ull << 16, 1ull << 16},
                        {3000, 1ull << 16, 1ull << 17},
                        {3000, 1, 1ull << 32},
                        {40000, 151, 23104},
                        {4096, 1ull << 32, 1ull << 32},
                        {3000, 70000, 1ull << 32}};
  uint32_t seed = 1;
  for (const Case& c : cases) {
    std::vector<SlotContact> pairs = RandomPairs(c.n, c.objects, c.triangles, seed++);
    std::vector<SlotContact> expected = pairs;
    std::sort(expected.begin(), expected.end());
    SortPairs(pairs);
    EXPECT_EQ(pairs, expected) << "n " << c.n << ", objects < " << c.objects << ", triangles < "
                               << c.triangles;
  }
}

TEST(PairSortTest, DistancePairsKeepTheirDistancesAndEqualPairsTheirOrder) {
  for (size_t n : {size_t{50}, size_t{2000}}) {
    // Few distinct pairs, so that many are equal: a stable sort keeps those in input order,
    // which the distances (the input positions) show.
    const std::vector<SlotContact> keys = RandomPairs(n, 3, 5, 7);
    std::vector<SlotDistancePair> pairs(n);
    for (size_t i = 0; i < n; ++i) pairs[i] = {keys[i], static_cast<double>(i)};
    std::vector<SlotDistancePair> expected = pairs;
    std::stable_sort(
        expected.begin(), expected.end(),
        [](const SlotDistancePair& x, const SlotDistancePair& y) { return x.pair < y.pair; });
    SortPairs(pairs);
    ASSERT_EQ(pairs.size(), expected.size());
    for (size_t i = 0; i < n; ++i) {
      EXPECT_EQ(pairs[i].pair, expected[i].pair) << "n " << n << ", at " << i;
      EXPECT_EQ(pairs[i].distance, expected[i].distance) << "n " << n << ", at " << i;
    }
  }
}

}  // namespace
}  // namespace far::internal
