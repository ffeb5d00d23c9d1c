#include "far/pairs/sweep_and_prune.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <random>
#include <span>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace far {
namespace {

SlotBox MakeBox(size_t slot, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return SlotBox{SlotAt(slot), Eigen::AlignedBox3d(lo, hi)};
}

// Pairs of slots given by their numbers.
std::vector<SlotPair> Pairs(std::initializer_list<std::pair<size_t, size_t>> pairs) {
  std::vector<SlotPair> slots;
  for (const auto& [a, b] : pairs) slots.push_back({SlotAt(a), SlotAt(b)});
  return slots;
}

// True iff a and b are non-empty and their gap is <= margin on every axis: the SAP contract.
bool WithinMargin(const Eigen::AlignedBox3d& a, const Eigen::AlignedBox3d& b, double margin) {
  if (a.isEmpty() || b.isEmpty()) return false;
  for (int axis = 0; axis < 3; ++axis) {
    if (b.min()[axis] - a.max()[axis] > margin) return false;
    if (a.min()[axis] - b.max()[axis] > margin) return false;
  }
  return true;
}

// The O(n^2) reference: every pair i < j by slot whose boxes are within margin.
std::vector<SlotPair> BruteForceOverlaps(const std::vector<SlotBox>& boxes, double margin) {
  std::vector<SlotPair> pairs;
  for (size_t i = 0; i < boxes.size(); ++i) {
    for (size_t j = i + 1; j < boxes.size(); ++j) {
      if (!WithinMargin(boxes[i].box_W, boxes[j].box_W, margin)) continue;
      pairs.push_back(
          {std::min(boxes[i].slot, boxes[j].slot), std::max(boxes[i].slot, boxes[j].slot)});
    }
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

void ExpectSortedAndOrdered(const std::vector<SlotPair>& pairs) {
  for (const SlotPair& pair : pairs) EXPECT_LT(pair.object_a, pair.object_b);
  for (size_t i = 1; i < pairs.size(); ++i) EXPECT_LT(pairs[i - 1], pairs[i]);
}

// Random boxes on a coarse grid (multiples of 1/4), so that equal and touching coordinates are
// common and every sum and difference is exact; about one box in eight has zero size on some
// axis and one in sixteen is a point.
class GridScene {
 public:
  explicit GridScene(uint32_t seed) : rng_(seed) {}

  double Coordinate(int cells) { return std::uniform_int_distribution<int>(0, cells)(rng_) / 4.0; }

  Eigen::AlignedBox3d RandomBox() {
    Eigen::Vector3d lo, hi;
    const int kind = std::uniform_int_distribution<int>(0, 15)(rng_);
    for (int axis = 0; axis < 3; ++axis) {
      lo[axis] = Coordinate(64);
      double size = Coordinate(12);
      if (kind == 0 || (kind < 3 && axis == kind)) size = 0;
      hi[axis] = lo[axis] + size;
    }
    return Eigen::AlignedBox3d(lo, hi);
  }

  // Moves the box by -1..1 grid cells per axis (often not at all).
  Eigen::AlignedBox3d Nudge(const Eigen::AlignedBox3d& box) {
    Eigen::Vector3d delta;
    for (int axis = 0; axis < 3; ++axis)
      delta[axis] = std::uniform_int_distribution<int>(-1, 1)(rng_) / 4.0;
    return Eigen::AlignedBox3d(box.min() + delta, box.max() + delta);
  }

  std::mt19937& rng() { return rng_; }

 private:
  std::mt19937 rng_;
};

TEST(SweepAndPruneTest, EmptyInputGivesNoPairs) {
  SweepAndPrune sap;
  EXPECT_TRUE(sap.Update({}).empty());
  EXPECT_TRUE(sap.Update({}, 1.0).empty());
  EXPECT_EQ(sap.last_swaps(), 0u);
}

TEST(SweepAndPruneTest, TouchingBoxesArePairs) {
  // A touches B on a face, C touches B on a corner, D is a point on A's face, E is apart.
  const std::vector<SlotBox> boxes = {
      MakeBox(10, {0, 0, 0}, {1, 1, 1}), MakeBox(20, {1, 0, 0}, {2, 1, 1}),
      MakeBox(30, {2, 1, 1}, {3, 2, 2}), MakeBox(40, {0, 0.5, 0.5}, {0, 0.5, 0.5}),
      MakeBox(50, {5, 5, 5}, {6, 6, 6}),
  };
  SweepAndPrune sap;
  const std::vector<SlotPair> expected = Pairs({{10, 20}, {10, 40}, {20, 30}});
  EXPECT_EQ(sap.Update(boxes), expected);
  EXPECT_EQ(BruteForceOverlaps(boxes, 0.0), expected);
}

TEST(SweepAndPruneTest, IdenticalAndDegenerateBoxesOverlap) {
  const std::vector<SlotBox> boxes = {
      MakeBox(3, {1, 1, 1}, {1, 1, 1}),
      MakeBox(1, {1, 1, 1}, {1, 1, 1}),
      MakeBox(2, {1, 1, 1}, {1, 1, 1}),
  };
  SweepAndPrune sap;
  const std::vector<SlotPair> expected = Pairs({{1, 2}, {1, 3}, {2, 3}});
  EXPECT_EQ(sap.Update(boxes), expected);
}

TEST(SweepAndPruneTest, MarginCountsGapUpToMarginOnEveryAxis) {
  // Gap 0.5 on x between 1 and 2; gap 0.5 on x and y between 1 and 3 (Euclidean 0.707).
  const std::vector<SlotBox> boxes = {
      MakeBox(1, {0, 0, 0}, {1, 1, 1}),
      MakeBox(2, {1.5, 0, 0}, {2.5, 1, 1}),
      MakeBox(3, {-1.5, 1.5, 0}, {-0.5, 2.5, 1}),
  };
  SweepAndPrune sap;
  EXPECT_TRUE(sap.Update(boxes, 0.0).empty());
  EXPECT_TRUE(sap.Update(boxes, 0.25).empty());
  EXPECT_EQ(sap.Update(boxes, 0.5), Pairs({{1, 2}, {1, 3}}));
  EXPECT_EQ(sap.Update(boxes, 0.4999999), std::vector<SlotPair>{});
  EXPECT_EQ(sap.Update(boxes, 4.0), Pairs({{1, 2}, {1, 3}, {2, 3}}));
}

TEST(SweepAndPruneTest, MarginIsNeverStricterThanTheGapAtAnyMagnitude) {
  // Coordinates where margin/2 is not representable relative to them.
  for (double offset : {0.0, 1e5, 1e9, -3e12}) {
    const double margin = 0.1;
    const std::vector<SlotBox> boxes = {
        MakeBox(1, {offset, 0, 0}, {offset + 1, 1, 1}),
        MakeBox(2, {offset + 1 + margin, 0, 0}, {offset + 2, 1, 1}),
    };
    SweepAndPrune sap;
    // The gap as computed in double may round either way; the pair must be there when it is
    // <= margin.
    if ((offset + 1 + margin) - (offset + 1) <= margin) {
      EXPECT_EQ(sap.Update(boxes, margin).size(), 1u) << "offset " << offset;
    }
  }
}

TEST(SweepAndPruneTest, EmptyAndNonFiniteBoxesPairWithNothing) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<SlotBox> boxes = {
      SlotBox{SlotAt(1), Eigen::AlignedBox3d()},  // empty
      MakeBox(2, {0, 0, 0}, {10, 10, 10}),       MakeBox(3, {nan, 0, 0}, {1, 1, 1}),
      MakeBox(4, {1, 1, 1}, {2, 2, 2}),          MakeBox(5, {0, 0, 0}, {inf, 1, 1}),
      MakeBox(6, {3, 3, 3}, {2, 4, 4}),  // inverted on x
  };
  SweepAndPrune sap;
  EXPECT_EQ(sap.Update(boxes), Pairs({{2, 4}}));
  EXPECT_EQ(sap.Update(boxes, 1.0), Pairs({{2, 4}}));
  // They keep the lists ordered for the others when the good boxes move.
  boxes[3] = MakeBox(4, {20, 20, 20}, {21, 21, 21});
  boxes.push_back(MakeBox(7, {20.5, 20.5, 20.5}, {22, 22, 22}));
  EXPECT_EQ(sap.Update(boxes), Pairs({{4, 7}}));
  // A pair whose boxes both turn empty, then come back.
  const SlotBox box_4 = boxes[3], box_7 = boxes.back();
  boxes[3].box_W = Eigen::AlignedBox3d();
  boxes.back().box_W = Eigen::AlignedBox3d();
  EXPECT_TRUE(sap.Update(boxes).empty());
  boxes[3].box_W.min().x() = nan;
  EXPECT_TRUE(sap.Update(boxes).empty());
  boxes[3] = box_4;
  boxes.back() = box_7;
  EXPECT_EQ(sap.Update(boxes), Pairs({{4, 7}}));
}

TEST(SweepAndPruneTest, UnchangedBoxesCostNoSwaps) {
  GridScene scene(7);
  std::vector<SlotBox> boxes;
  for (uint32_t i = 0; i < 300; ++i) boxes.push_back({SlotAt(i * 3 + 1), scene.RandomBox()});
  SweepAndPrune sap;
  const std::vector<SlotPair> first = sap.Update(boxes, 0.5);
  for (int step = 0; step < 3; ++step) {
    EXPECT_EQ(sap.Update(boxes, 0.5), first);
    EXPECT_EQ(sap.last_swaps(), 0u);
  }
  // Input order does not matter, and reordering is not motion.
  std::reverse(boxes.begin(), boxes.end());
  EXPECT_EQ(sap.Update(boxes, 0.5), first);
  EXPECT_EQ(sap.last_swaps(), 0u);
}

TEST(SweepAndPruneTest, SmallMotionsCostFewSwaps) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> position(0, 100), size(0, 2), jitter(-1e-3, 1e-3);
  std::vector<SlotBox> boxes;
  for (uint32_t i = 0; i < 1000; ++i) {
    const Eigen::Vector3d lo(position(rng), position(rng), position(rng));
    boxes.push_back({SlotAt(i), Eigen::AlignedBox3d(
                                    lo, lo + Eigen::Vector3d(size(rng), size(rng), size(rng)))});
  }
  SweepAndPrune sap;
  sap.Update(boxes);
  const size_t num_endpoints = 6 * boxes.size();
  for (int step = 0; step < 5; ++step) {
    for (SlotBox& box : boxes) {
      const Eigen::Vector3d delta(jitter(rng), jitter(rng), jitter(rng));
      box.box_W = Eigen::AlignedBox3d(box.box_W.min() + delta, box.box_W.max() + delta);
    }
    EXPECT_EQ(sap.Update(boxes), BruteForceOverlaps(boxes, 0.0));
    EXPECT_LT(sap.last_swaps(), num_endpoints / 10) << "step " << step;
  }
  // A scene that jumps is still right (and re-sorted rather than insertion-sorted).
  std::shuffle(boxes.begin(), boxes.end(), rng);
  for (uint32_t i = 0; i < boxes.size(); ++i) boxes[i].slot = SlotAt(i);
  EXPECT_EQ(sap.Update(boxes), BruteForceOverlaps(boxes, 0.0));
  EXPECT_GT(sap.last_swaps(), num_endpoints / 10);
}

TEST(SweepAndPruneTest, RemovedSlotCanComeBack) {
  SweepAndPrune sap;
  std::vector<SlotBox> boxes = {MakeBox(5, {0, 0, 0}, {1, 1, 1}),
                                MakeBox(9, {0.5, 0, 0}, {2, 1, 1})};
  EXPECT_EQ(sap.Update(boxes), Pairs({{5, 9}}));
  EXPECT_TRUE(sap.Update(std::span(boxes).first(1)).empty());
  EXPECT_TRUE(sap.Update({}).empty());
  boxes[0] = MakeBox(5, {1.5, 0.5, 0.5}, {3, 3, 3});
  EXPECT_EQ(sap.Update(boxes), Pairs({{5, 9}}));
}

TEST(SweepAndPruneTest, ASlotGivenToAnotherObjectInOneUpdateIsAMove) {
  // The scene cache frees a removed object's slot and gives it to the next object added, maybe
  // in the same update: sweep-and-prune sees one slot whose box jumped.
  SweepAndPrune sap;
  std::vector<SlotBox> boxes = {MakeBox(0, {0, 0, 0}, {1, 1, 1}),
                                MakeBox(1, {0.5, 0, 0}, {2, 1, 1}),
                                MakeBox(2, {10, 10, 10}, {11, 11, 11})};
  EXPECT_EQ(sap.Update(boxes), Pairs({{0, 1}}));
  boxes[1] = MakeBox(1, {10.5, 10.5, 10.5}, {12, 12, 12});  // another object in slot 1
  EXPECT_EQ(sap.Update(boxes), Pairs({{1, 2}}));
  EXPECT_EQ(sap.Update(boxes), BruteForceOverlaps(boxes, 0.0));
}

TEST(SweepAndPruneTest, RandomScenesMatchBruteForceAcrossSteps) {
  for (uint32_t seed : {1u, 2u, 3u, 4u, 5u, 6u}) {
    for (int num_objects : {0, 1, 2, 17, 150, 400}) {
      GridScene scene(seed * 1000 + num_objects);
      const double margin = std::vector<double>{0.0, 0.25, 1.25}[seed % 3];
      // Slots as the scene cache hands them out: dense, and a freed slot is taken by the next
      // object added (on even seeds; odd seeds leave holes).
      uint32_t next_slot = 0;
      std::vector<ObjectSlot> free_slots;
      const auto new_slot = [&] {
        if (seed % 2 == 0 && !free_slots.empty()) {
          const ObjectSlot slot = free_slots.back();
          free_slots.pop_back();
          return slot;
        }
        return SlotAt(next_slot++);
      };
      std::vector<SlotBox> boxes;
      for (int i = 0; i < num_objects; ++i) boxes.push_back({new_slot(), scene.RandomBox()});
      SweepAndPrune sap;
      for (int step = 0; step < 12; ++step) {
        SCOPED_TRACE(::testing::Message()
                     << "seed " << seed << " objects " << num_objects << " step " << step);
        const std::vector<SlotPair> pairs = sap.Update(boxes, margin);
        ExpectSortedAndOrdered(pairs);
        ASSERT_EQ(pairs, BruteForceOverlaps(boxes, margin));

        // Next step: most objects nudge, a few are removed, a few turn empty (inverted) or
        // back, a few are added.
        std::uniform_int_distribution<int> percent(0, 99);
        std::vector<SlotBox> next;
        for (const SlotBox& box : boxes) {
          const int roll = percent(scene.rng());
          if (roll < 5) {
            free_slots.push_back(box.slot);
            continue;
          }
          if (roll < 8) {
            const Eigen::Vector3d corner = box.box_W.max();
            next.push_back(
                {box.slot, box.box_W.isEmpty()
                               ? scene.RandomBox()
                               : Eigen::AlignedBox3d(corner + Eigen::Vector3d::Ones(), corner)});
            continue;
          }
          next.push_back({box.slot, roll < 60 ? scene.Nudge(box.box_W) : box.box_W});
        }
        const int num_added =
            std::uniform_int_distribution<int>(0, 1 + num_objects / 20)(scene.rng());
        for (int i = 0; i < num_added; ++i) next.push_back({new_slot(), scene.RandomBox()});
        std::shuffle(next.begin(), next.end(), scene.rng());
        boxes = std::move(next);
      }
    }
  }
}

TEST(SweepAndPruneTest, RandomRealScenesBracketBruteForce) {
  // Off-grid coordinates: sums round, so compare against a slightly smaller and a slightly
  // larger margin: SAP must find every pair of the first and nothing outside the second.
  for (uint32_t seed : {21u, 22u, 23u}) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> position(-50, 50), size(0, 5), jitter(-0.2, 0.2);
    const double margin = 0.37 * seed / 10;
    std::vector<SlotBox> boxes;
    for (uint32_t i = 0; i < 300; ++i) {
      const Eigen::Vector3d lo(position(rng), position(rng), position(rng));
      boxes.push_back({SlotAt(i), Eigen::AlignedBox3d(
                                      lo, lo + Eigen::Vector3d(size(rng), size(rng), size(rng)))});
    }
    SweepAndPrune sap;
    for (int step = 0; step < 8; ++step) {
      const std::vector<SlotPair> pairs = sap.Update(boxes, margin);
      ExpectSortedAndOrdered(pairs);
      const std::vector<SlotPair> inner = BruteForceOverlaps(boxes, margin * (1 - 1e-9));
      const std::vector<SlotPair> outer = BruteForceOverlaps(boxes, margin * (1 + 1e-9));
      EXPECT_TRUE(std::includes(pairs.begin(), pairs.end(), inner.begin(), inner.end()));
      EXPECT_TRUE(std::includes(outer.begin(), outer.end(), pairs.begin(), pairs.end()));
      for (SlotBox& box : boxes) {
        const Eigen::Vector3d delta(jitter(rng), jitter(rng), jitter(rng));
        box.box_W = Eigen::AlignedBox3d(box.box_W.min() + delta, box.box_W.max() + delta);
      }
    }
  }
}

}  // namespace
}  // namespace far
