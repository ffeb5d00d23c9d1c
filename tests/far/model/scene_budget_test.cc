// The fair shares of a daemon's budgets (far/model/scene_budget.h): a user alone may use all of
// a budget, a user within its share is never refused for room another holds above its share,
// and every refusal names the user, its share and the users sharing the total.
#include "far/model/scene_budget.h"

#include <map>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "far/model/scene_model.h"

namespace far {
namespace {

constexpr int64_t kMillion = 1'000'000;

::testing::AssertionResult IsError(const Result<void>& result, ErrorCode code,
                                   const std::string& part) {
  if (result) return ::testing::AssertionFailure() << "no error";
  if (result.error().code != code || result.error().message.find(part) == std::string::npos)
    return ::testing::AssertionFailure() << ToString(result.error());
  return ::testing::AssertionSuccess();
}

BudgetAmounts Triangles(int64_t triangles) { return BudgetAmounts::Scene(0, triangles); }

// The daemon's defaults: 64 sessions, 16M vertices, 8M triangles (bytes unlimited here).
BudgetAmounts Defaults() {
  BudgetAmounts totals = BudgetAmounts::Scene(16 * kMillion, 8 * kMillion);
  totals[BudgetKind::kSessions] = 64;
  totals[BudgetKind::kSegmentBytes] = SharedSceneBudget::kUnlimited;
  return totals;
}

// Every holder the budget closed to make room, with why.
struct Reclaimed {
  std::vector<std::pair<int64_t, Error>> closed;
  void Watch(SharedSceneBudget& budget) {
    budget.OnReclaim([this](int64_t holder, const Error& why) { closed.push_back({holder, why}); });
  }
};

TEST(FairShareTest, IsTheTotalOverTheUsersAndNeverLessThanOne) {
  EXPECT_EQ(FairShare(8 * kMillion, 1), 8 * kMillion);
  EXPECT_EQ(FairShare(8 * kMillion, 2), 4 * kMillion);
  EXPECT_EQ(FairShare(8 * kMillion, 3), 2'666'666);
  EXPECT_EQ(FairShare(64, 5), 12);
  EXPECT_EQ(FairShare(64, 100), 1);
  EXPECT_EQ(FairShare(64, 0), 64);
}

TEST(FairShareTest, AmountsAreWrittenForPeople) {
  EXPECT_EQ(FormatAmount(BudgetKind::kTriangles, 960), "960");
  EXPECT_EQ(FormatAmount(BudgetKind::kTriangles, 4 * kMillion), "4.0M");
  EXPECT_EQ(FormatAmount(BudgetKind::kVertices, 266'666), "266.7K");
  EXPECT_EQ(FormatAmount(BudgetKind::kSessions, 12), "12");
  EXPECT_EQ(FormatAmount(BudgetKind::kSegmentBytes, int64_t{80} << 20), "80 MiB");
  EXPECT_EQ(FormatAmount(BudgetKind::kSegmentBytes, int64_t{5} << 30), "5.0 GiB");
}

TEST(SharedSceneBudgetTest, AUserAloneMayUseAllOfIt) {
  SharedSceneBudget budget(Defaults());
  for (int64_t holder = 1; holder <= 4; ++holder) {
    ASSERT_TRUE(budget.Admit(holder, 1001, BudgetAmounts::Session(0)));
    ASSERT_TRUE(budget.Reserve(holder, Triangles(2 * kMillion)));
  }
  EXPECT_EQ(budget.triangles(), 8 * kMillion);
  EXPECT_EQ(budget.users(), 1);
  // Full: one more triangle of its own is refused, naming its share (all of it).
  EXPECT_TRUE(IsError(budget.Reserve(1, Triangles(1)), ErrorCode::kLimitExceeded,
                      "max_triangles_total: user 1001 holds 8.0M of its share of 8.0M triangles "
                      "(8.0M shared by 1 user); 1 more would pass its share, and 0 are free"));
}

// The attack of issue 41: one user's idle sessions held the whole triangle budget, and every
// other user's upload was refused for as long as they stayed open.
TEST(SharedSceneBudgetTest, AUserWithinItsShareGetsRoomFromTheUserAboveIt) {
  SharedSceneBudget budget(Defaults());
  Reclaimed reclaimed;
  reclaimed.Watch(budget);
  for (int64_t holder = 1; holder <= 4; ++holder) {
    ASSERT_TRUE(budget.Admit(holder, 1001, BudgetAmounts::Session(0)));
    ASSERT_TRUE(budget.Reserve(holder, Triangles(2 * kMillion)));
  }
  // Holder 2 is the one that has gone longest without a step.
  for (int64_t holder : {3, 4, 1}) budget.Touch(holder);

  ASSERT_TRUE(budget.Admit(10, 0, BudgetAmounts::Session(0)));
  EXPECT_EQ(budget.ShareOf(0, BudgetKind::kTriangles), 4 * kMillion);
  ASSERT_TRUE(budget.Reserve(10, Triangles(1024)));

  ASSERT_EQ(reclaimed.closed.size(), 1u);
  EXPECT_EQ(reclaimed.closed[0].first, 2);
  EXPECT_EQ(reclaimed.closed[0].second.code, ErrorCode::kLimitExceeded);
  EXPECT_NE(reclaimed.closed[0].second.message.find(
                "session closed to make room for user 0, which is within its share: user 1001 "
                "holds 8.0M of its share of 4.0M triangles (8.0M shared by 2 users), and of its "
                "sessions this one (2.0M triangles) had gone longest without a step"),
            std::string::npos)
      << reclaimed.closed[0].second.message;
  EXPECT_EQ(budget.HeldBy(1001)[BudgetKind::kTriangles], 6 * kMillion);
  EXPECT_EQ(budget.HeldBy(0)[BudgetKind::kTriangles], 1024);
  EXPECT_EQ(budget.triangles(), 6 * kMillion + 1024);
  // The closed holder grows no more, gives back nothing twice, and leaves.
  EXPECT_TRUE(
      IsError(budget.Reserve(2, Triangles(1)), ErrorCode::kLimitExceeded, "closed to make room"));
  budget.Release(2, Triangles(2 * kMillion));
  budget.Leave(2);
  EXPECT_EQ(budget.triangles(), 6 * kMillion + 1024);
}

TEST(SharedSceneBudgetTest, AUserAtItsShareIsRefusedNamingTheRuleAndNobodyLosesASession) {
  SharedSceneBudget budget(Defaults());
  Reclaimed reclaimed;
  reclaimed.Watch(budget);
  ASSERT_TRUE(budget.Admit(1, 1001, Triangles(4 * kMillion)));
  ASSERT_TRUE(budget.Admit(2, 1002, Triangles(4 * kMillion)));
  const auto refused = budget.Reserve(1, Triangles(2 * kMillion));
  EXPECT_TRUE(IsError(refused, ErrorCode::kLimitExceeded,
                      "max_triangles_total: user 1001 holds 4.0M of its share of 4.0M triangles "
                      "(8.0M shared by 2 users); 2.0M more would pass its share, and 0 are free"));
  EXPECT_TRUE(reclaimed.closed.empty());
  EXPECT_EQ(budget.triangles(), 8 * kMillion);
}

TEST(SharedSceneBudgetTest, AUserAboveItsShareMayStillUseWhatIsFree) {
  SharedSceneBudget budget(Defaults());
  ASSERT_TRUE(budget.Admit(1, 1001, Triangles(6 * kMillion)));
  ASSERT_TRUE(budget.Admit(2, 1002, Triangles(kMillion)));
  EXPECT_TRUE(budget.Reserve(1, Triangles(kMillion)));
  EXPECT_EQ(budget.HeldBy(1001)[BudgetKind::kTriangles], 7 * kMillion);
}

// The other attack: four users with 16 sessions each held every one of the 64 slots.
TEST(SharedSceneBudgetTest, MoreSessionsDoNotBuyALargerShareOfTheSlots) {
  SharedSceneBudget budget(Defaults());
  Reclaimed reclaimed;
  reclaimed.Watch(budget);
  int64_t next = 1;
  for (uint32_t user = 1001; user <= 1004; ++user) {
    for (int i = 0; i < 16; ++i) ASSERT_TRUE(budget.Admit(next++, user, BudgetAmounts::Session(0)));
  }
  // A fifth user: 64 / 5 = 12 sessions are its share, each taken from the user furthest above.
  for (int i = 0; i < 12; ++i)
    ASSERT_TRUE(budget.Admit(next++, 0, BudgetAmounts::Session(0))) << "session " << i;
  EXPECT_EQ(reclaimed.closed.size(), 12u);
  for (uint32_t user = 1001; user <= 1004; ++user)
    EXPECT_EQ(budget.HeldBy(user)[BudgetKind::kSessions], 13) << user;
  EXPECT_TRUE(IsError(budget.Admit(next++, 0, BudgetAmounts::Session(0)), ErrorCode::kLimitExceeded,
                      "max_sessions: user 0 holds 12 of its share of 12 sessions (64 shared by 5 "
                      "users); 1 more would pass its share, and 0 are free"));
  EXPECT_EQ(reclaimed.closed.size(), 12u);
}

TEST(SharedSceneBudgetTest, WhenEveryoneIsWithinItsShareANewUserIsRefused) {
  BudgetAmounts totals = Defaults();
  totals[BudgetKind::kSessions] = 2;
  SharedSceneBudget budget(totals);
  ASSERT_TRUE(budget.Admit(1, 1001, BudgetAmounts::Session(0)));
  ASSERT_TRUE(budget.Admit(2, 1002, BudgetAmounts::Session(0)));
  // Three users: a share of 1 (never less), which the two hold.
  EXPECT_TRUE(IsError(budget.Admit(3, 1003, BudgetAmounts::Session(0)), ErrorCode::kLimitExceeded,
                      "max_sessions: 2 sessions are held by 2 other users, each within its share "
                      "of 1"));
  EXPECT_EQ(budget.users(), 2);
}

TEST(SharedSceneBudgetTest, LeavingGivesEverythingBackAndTheUserGoes) {
  SharedSceneBudget budget(Defaults());
  ASSERT_TRUE(budget.Admit(1, 1001, BudgetAmounts::Session(4096)));
  ASSERT_TRUE(budget.Reserve(1, BudgetAmounts::Scene(30, 10)));
  budget.Release(1, BudgetAmounts::Scene(3, 1));
  EXPECT_EQ(budget.vertices(), 27);
  EXPECT_EQ(budget.triangles(), 9);
  budget.Leave(1);
  for (BudgetKind kind : {BudgetKind::kSessions, BudgetKind::kSegmentBytes, BudgetKind::kVertices,
                          BudgetKind::kTriangles})
    EXPECT_EQ(budget.used(kind), 0) << ToString(kind);
  EXPECT_EQ(budget.users(), 0);
  EXPECT_TRUE(IsError(budget.Reserve(1, Triangles(1)), ErrorCode::kNotFound, "never admitted"));
  ASSERT_TRUE(budget.Admit(2, 1001, {}));
  EXPECT_TRUE(IsError(budget.Admit(2, 1001, {}), ErrorCode::kInvalidArgument, "already admitted"));
}

// Random admits, growths, releases and leaves of 5 users: the totals always hold, and a
// refusal only ever comes to a user that would pass its share.
TEST(SharedSceneBudgetTest, RandomUseNeverRefusesAUserWithinItsShare) {
  SharedSceneBudget budget(Defaults());
  std::map<int64_t, uint32_t> owner;  // holders alive (not closed to make room)
  budget.OnReclaim([&](int64_t holder, const Error&) { owner.erase(holder); });
  std::mt19937 random(41);
  int64_t next = 1;
  int refused = 0;
  for (int op = 0; op < 20'000; ++op) {
    const uint32_t user = 1000 + random() % 5;
    std::vector<int64_t> mine;
    for (const auto& [holder, u] : owner)
      if (u == user) mine.push_back(holder);
    const int choice = random() % 10;
    if (mine.empty() || choice == 0) {
      const int64_t share = budget.ShareOf(user, BudgetKind::kSessions);
      const int64_t held = budget.HeldBy(user)[BudgetKind::kSessions];
      auto admitted = budget.Admit(next, user, BudgetAmounts::Session(0));
      if (admitted) owner[next] = user;
      if (!admitted) ++refused;
      EXPECT_TRUE(admitted || held + 1 > share) << op << ": " << ToString(admitted.error());
      ++next;
    } else if (choice == 1) {
      const int64_t holder = mine[random() % mine.size()];
      budget.Leave(holder);
      owner.erase(holder);
    } else if (choice <= 3) {
      budget.Release(mine[random() % mine.size()], Triangles(random() % 500'000));
    } else {
      const int64_t more = random() % 1'500'000;
      const int64_t share = budget.ShareOf(user, BudgetKind::kTriangles);
      const int64_t held = budget.HeldBy(user)[BudgetKind::kTriangles];
      auto grown = budget.Reserve(mine[random() % mine.size()], Triangles(more));
      if (!grown) ++refused;
      EXPECT_TRUE(grown || held + more > share) << op << ": " << ToString(grown.error());
    }
    ASSERT_LE(budget.triangles(), 8 * kMillion);
    ASSERT_LE(budget.used(BudgetKind::kSessions), 64);
  }
  EXPECT_GT(refused, 100) << "the budget was never full: nothing was tested";
}

TEST(SharedSceneBudgetTest, ASceneModelDrawsFromItsHolder) {
  SharedSceneBudget budget(100, 10);
  ASSERT_TRUE(budget.Admit(7, 1001, {}));
  {
    SceneModel model({}, &budget, 7);
    Mesh mesh;
    mesh.p_MV = {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()};
    mesh.triangles = {{0, 1, 2}, {0, 2, 1}};
    const SceneUpdate add[] = {AddObject{1, mesh, Motion::kStatic, {}}};
    ASSERT_TRUE(model.Apply(add));
    EXPECT_EQ(budget.HeldBy(1001)[BudgetKind::kTriangles], 2);
    EXPECT_EQ(budget.HeldBy(1001)[BudgetKind::kVertices], 3);
  }
  EXPECT_EQ(budget.triangles(), 0);
}

}  // namespace
}  // namespace far
