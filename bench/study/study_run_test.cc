// far-study's plan of a scene's steps: where the brute-force reference runs (--reference-steps)
// and in which order the configurations run at each step.

#include "study_run.h"

#include <algorithm>
#include <numeric>
#include <optional>
#include <set>
#include <vector>

#include <gtest/gtest.h>

namespace far_study {
namespace {

TEST(ReferenceStepsTest, EveryStepByDefaultOrWhenAskedForAsManyOrMore) {
  EXPECT_EQ(ReferenceSteps(4, 0, {}), (std::vector<int>{1, 2, 3, 4}));
  EXPECT_EQ(ReferenceSteps(4, 4, {}), (std::vector<int>{1, 2, 3, 4}));
  EXPECT_EQ(ReferenceSteps(3, 9, {2}), (std::vector<int>{1, 2, 3}));
}

TEST(ReferenceStepsTest, SpreadsEvenlyWithTheFirstAndTheLast) {
  EXPECT_EQ(ReferenceSteps(4, 1, {}), (std::vector<int>{1}));
  EXPECT_EQ(ReferenceSteps(4, 2, {}), (std::vector<int>{1, 4}));
  EXPECT_EQ(ReferenceSteps(6, 3, {}), (std::vector<int>{1, 4, 6}));
  EXPECT_EQ(ReferenceSteps(9, 3, {}), (std::vector<int>{1, 5, 9}));
}

TEST(ReferenceStepsTest, AlwaysHasTheKeyStepsInRange) {
  // breaking with 4 steps breaks at 2; 6 steps at 3.
  EXPECT_EQ(ReferenceSteps(4, 1, {2, 3}), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(ReferenceSteps(6, 2, {3, 4}), (std::vector<int>{1, 3, 4, 6}));
  EXPECT_EQ(ReferenceSteps(6, 2, {0, 7}), (std::vector<int>{1, 6}));
}

TEST(StepOrderTest, EveryStepRunsEveryConfigurationOnce) {
  for (size_t count = 0; count <= 30; ++count) {
    for (int s = 0; s <= 40; ++s) {
      std::vector<size_t> order = StepOrder(count, s);
      ASSERT_EQ(order.size(), count) << "count " << count << " step " << s;
      std::sort(order.begin(), order.end());
      std::vector<size_t> all(count);
      std::iota(all.begin(), all.end(), size_t{0});
      EXPECT_EQ(order, all) << "count " << count << " step " << s;
    }
  }
}

TEST(StepOrderTest, TheFirstRotatesByOnePerStep) {
  for (int s = 0; s < 26; ++s) EXPECT_EQ(StepOrder(13, s).front(), static_cast<size_t>(s % 13));
}

// The configuration right after `last` at step s (none when `last` runs last).
std::optional<size_t> Successor(size_t count, int s, size_t last) {
  const std::vector<size_t> order = StepOrder(count, s);
  const auto it = std::find(order.begin(), order.end(), last);
  if (it + 1 == order.end()) return std::nullopt;
  return *(it + 1);
}

// The reference is the last configuration: a plain rotation had the same one follow it at every
// step. 13 configurations (a paper-scale scene): twelve steps, twelve different successors.
TEST(StepOrderTest, TheOneAfterTheReferenceChangesFromStepToStep) {
  std::set<size_t> successors;
  for (int s = 1; s <= 12; ++s) {
    if (auto next = Successor(13, s, 12)) successors.insert(*next);
  }
  EXPECT_EQ(successors.size(), 12u);
  // 6 configurations (a small scaling size): consecutive steps differ.
  for (int s = 1; s < 8; ++s) {
    auto a = Successor(6, s, 5), b = Successor(6, s + 1, 5);
    if (a && b) {
      EXPECT_NE(*a, *b) << "steps " << s << " and " << s + 1;
    }
  }
}

}  // namespace
}  // namespace far_study
