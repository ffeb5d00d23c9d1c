// A session's steps by id: repeats are told from new steps, answers are kept within bounds, and
// a repeat finds its step's answer, its stage or its place in the queue.

#include "step_ledger.h"

#include <deque>

#include "session.h"
#include <gtest/gtest.h>

namespace far::server {
namespace {

using Kind = StepRecall::Kind;

std::vector<uint8_t> Bytes(size_t n, uint8_t value) { return std::vector<uint8_t>(n, value); }

StepJob Job(int64_t step_id, int64_t request_id) {
  StepJob job;
  job.command.step_id = step_id;
  job.command.request_id = request_id;
  job.received = Clock::now();
  return job;
}

TEST(StepLedgerTest, AStepIdAtOrBelowTheHighestTakenIsARepeat) {
  StepLedger ledger;
  EXPECT_TRUE(ledger.Take(0));
  EXPECT_FALSE(ledger.Take(0));
  EXPECT_TRUE(ledger.Take(5));  // ids may skip
  EXPECT_FALSE(ledger.Take(3));
  EXPECT_FALSE(ledger.Take(5));
  // A negative id is invalid, answered as such, and never taken.
  EXPECT_TRUE(ledger.Take(-1));
  EXPECT_TRUE(ledger.Take(6));
}

TEST(StepLedgerTest, ARepeatFindsWhereItsStepIs) {
  StepLedger ledger;
  std::deque<StepJob> queue;
  for (int64_t step = 0; step < 3; ++step) ASSERT_TRUE(ledger.Take(step));
  queue.push_back(Job(1, 11));
  queue.push_back(Job(2, 12));
  ledger.Start(0, 10, Clock::now());
  StepRecall running = ledger.Recall(0, queue);
  EXPECT_EQ(running.kind, Kind::kRunning);
  EXPECT_EQ(running.request_id, 10);
  EXPECT_FALSE(running.stage.has_value());
  ledger.EnterStage(Stage::kExact);
  EXPECT_EQ(ledger.Recall(0, queue).stage, Stage::kExact);
  StepRecall queued = ledger.Recall(2, queue);
  EXPECT_EQ(queued.kind, Kind::kQueued);
  EXPECT_EQ(queued.queue_position, 1);
  EXPECT_EQ(queued.request_id, 12);
  // Answered: the answer, byte for byte; the step is no longer running.
  ledger.Keep(0, Bytes(100, 7));
  StepRecall answered = ledger.Recall(0, queue);
  EXPECT_EQ(answered.kind, Kind::kAnswered);
  EXPECT_EQ(answered.reply, Bytes(100, 7));
  EXPECT_EQ(ledger.Recall(7, queue).kind, Kind::kForgotten);
}

TEST(StepLedgerTest, KeepsTheLastFewAnswersWithinItsBytesAndAlwaysTheNewest) {
  StepLedger ledger;
  const std::deque<StepJob> none;
  for (int64_t step = 0; step < 6; ++step)
    ledger.Keep(step, Bytes(1000, static_cast<uint8_t>(step)));
  EXPECT_EQ(ledger.Recall(1, none).kind, Kind::kForgotten);
  EXPECT_EQ(ledger.Recall(2, none).kind, Kind::kAnswered);
  EXPECT_EQ(ledger.kept_bytes(), StepLedger::kMaxKept * 1000);
  // Beyond the newest, at most kMaxKeptBytes are kept: large answers push older ones out.
  ledger.Keep(6, Bytes(StepLedger::kMaxKeptBytes - 500, 6));
  ledger.Keep(7, Bytes(1000, 7));
  EXPECT_EQ(ledger.Recall(5, none).kind, Kind::kForgotten);
  EXPECT_EQ(ledger.Recall(6, none).kind, Kind::kAnswered);
  EXPECT_EQ(ledger.kept_bytes(), StepLedger::kMaxKeptBytes + 500);
  // The newest stays whatever its size.
  ledger.Keep(8, Bytes(2 * StepLedger::kMaxKeptBytes, 8));
  EXPECT_EQ(ledger.Recall(6, none).kind, Kind::kForgotten);
  EXPECT_EQ(ledger.Recall(7, none).kind, Kind::kAnswered);
  ledger.Keep(9, Bytes(10, 9));
  EXPECT_EQ(ledger.Recall(8, none).kind, Kind::kForgotten);
  EXPECT_EQ(ledger.kept_bytes(), 10u);
}

TEST(StepLedgerTest, AStepOverWithoutAnAnswerIsNoLongerRunning) {
  StepLedger ledger;
  const std::deque<StepJob> none;
  ASSERT_TRUE(ledger.Take(0));
  ledger.Start(0, 1, Clock::now());
  ledger.Finish();
  EXPECT_EQ(ledger.Recall(0, none).kind, Kind::kForgotten);
}

}  // namespace
}  // namespace far::server
