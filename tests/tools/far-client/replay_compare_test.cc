// far-client replay's verdict per step (docs/record-replay.md, "What matches").
#include "replay_compare.h"

#include <gtest/gtest.h>

namespace far::cli {
namespace {

StepResult Reliable(const std::string& method) {
  StepResult r;
  r.contacts = {{1, 0, 2, 3}, {1, 4, 2, 5}};
  r.distance_pairs = {{{1, 0, 2, 3}, 0}, {{1, 6, 2, 7}, 0.25}};
  r.pcs_objects = {1, 2};
  r.object_pairs = {{1, 2}};
  r.pcs_primitives = {{1, {0, 4, 6}}, {2, {3, 5, 7}}};
  r.stats.method = method;
  r.stats.certificate.guaranteed = true;
  return r;
}

CompareOptions SameRenderer() { return {true, false}; }
CompareOptions OtherRenderer() { return {false, false}; }

TEST(ReplayCompareTest, IdenticalRepliesMatch) {
  const auto c =
      CompareStep(Reliable("far/id-buffer/128"), Reliable("far/id-buffer/128"), SameRenderer());
  EXPECT_TRUE(c.compared);
  EXPECT_TRUE(c.matches());
  EXPECT_TRUE(c.notes.empty());
  EXPECT_EQ(c.summary,
            "contacts 2, distance pairs 2, pcs 2 objects / 6 triangles, "
            "far/id-buffer/128");
}

TEST(ReplayCompareTest, AMissingOrExtraContactFailsEverywhereAndIsNamed) {
  StepResult fewer = Reliable("bvh");
  fewer.contacts.pop_back();
  const auto missing = CompareStep(Reliable("bvh"), fewer, OtherRenderer());
  ASSERT_FALSE(missing.matches());
  EXPECT_EQ(missing.mismatches.front(),
            "contact (object 1 triangle 4, object 2 triangle 5) recorded, not replayed (2 "
            "recorded, 1 replayed)");
  const auto extra = CompareStep(fewer, Reliable("bvh"), OtherRenderer());
  ASSERT_FALSE(extra.matches());
  EXPECT_NE(extra.mismatches.front().find("replayed, not recorded"), std::string::npos);
}

TEST(ReplayCompareTest, DistancePairsAndTheirDistancesMustMatch) {
  StepResult moved = Reliable("bvh");
  moved.distance_pairs[1].distance = 0.2500001;
  const auto c = CompareStep(Reliable("bvh"), moved, OtherRenderer());
  ASSERT_FALSE(c.matches());
  EXPECT_NE(c.mismatches.front().find("distance of pair (object 1 triangle 6"), std::string::npos)
      << c.mismatches.front();
  StepResult rounded = Reliable("bvh");
  rounded.distance_pairs[1].distance = 0.25 + 1e-15;  // a last-bit difference is no mismatch
  EXPECT_TRUE(CompareStep(Reliable("bvh"), rounded, OtherRenderer()).matches());
}

TEST(ReplayCompareTest, PcsDifferencesFailOnlyInTheSameConfigurationOrStrict) {
  StepResult wider = Reliable("far/id-buffer/128");
  wider.pcs_primitives[2].push_back(9);
  wider.pcs_objects.push_back(3);
  const auto same = CompareStep(Reliable("far/id-buffer/128"), wider, SameRenderer());
  EXPECT_FALSE(same.matches());
  const auto other = CompareStep(Reliable("far/id-buffer/128"), wider, OtherRenderer());
  EXPECT_TRUE(other.matches());
  EXPECT_EQ(other.notes.size(), 2u);  // PCS objects and triangles
  const auto strict = CompareStep(Reliable("far/id-buffer/128"), wider, {false, true});
  EXPECT_FALSE(strict.matches());
  // auto chose another method this time: the PCS may differ, the contacts may not.
  const auto chose = CompareStep(Reliable("bvh"), wider, SameRenderer());
  EXPECT_TRUE(chose.matches());
  EXPECT_NE(chose.notes.back().find("method bvh recorded, far/id-buffer/128 replayed"),
            std::string::npos);
}

TEST(ReplayCompareTest, AContactOutsideAReliablePcsFails) {
  StepResult hole = Reliable("far/id-buffer/128");
  hole.pcs_primitives[2] = {3, 7};  // triangle 5 of object 2 is in a contact
  const auto c = CompareStep(hole, hole, OtherRenderer());
  ASSERT_FALSE(c.matches());
  EXPECT_NE(c.mismatches.front().find("outside the replayed PCS"), std::string::npos);
}

TEST(ReplayCompareTest, CullideContactsAreExactOnlyOnTheSameRenderer) {
  StepResult cullide = Reliable("cullide/id-buffer/128");
  cullide.stats.certificate.guaranteed = false;
  StepResult fewer = cullide;
  fewer.contacts.pop_back();
  EXPECT_FALSE(CompareStep(cullide, fewer, SameRenderer()).matches());
  const auto other = CompareStep(cullide, fewer, OtherRenderer());
  EXPECT_TRUE(other.matches());
  EXPECT_FALSE(other.notes.empty());
}

TEST(ReplayCompareTest, RecordedFailuresCompareByCodeAndClientSideEndsAreNotCompared) {
  const Result<StepResult> refused = MakeError(ErrorCode::kInvalidArgument, "bad record 3");
  const Result<StepResult> refused_again = MakeError(ErrorCode::kInvalidArgument, "other words");
  EXPECT_TRUE(CompareStep(refused, refused_again, OtherRenderer()).matches());
  EXPECT_FALSE(CompareStep(refused, Reliable("bvh"), OtherRenderer()).matches());
  EXPECT_FALSE(
      CompareStep(refused, MakeError(ErrorCode::kLimitExceeded, "x"), OtherRenderer()).matches());
  const auto timeout =
      CompareStep(MakeError(ErrorCode::kTimeout, "timeout"), Reliable("bvh"), OtherRenderer());
  EXPECT_FALSE(timeout.compared);
  EXPECT_TRUE(timeout.matches());
  EXPECT_FALSE(
      CompareStep(Reliable("bvh"), MakeError(ErrorCode::kTimeout, "t"), OtherRenderer()).matches());
}

}  // namespace
}  // namespace far::cli
