#include "step_ledger.h"

#include <algorithm>

#include "session.h"

namespace far::server {

bool StepLedger::Take(int64_t step_id) {
  if (step_id < 0) return true;
  if (step_id <= last_step_id_) return false;
  last_step_id_ = step_id;
  return true;
}

void StepLedger::Start(int64_t step_id, int64_t request_id,
                       std::chrono::steady_clock::time_point received) {
  running_ = Running{step_id, request_id, received, std::nullopt};
}

void StepLedger::EnterStage(Stage stage) {
  if (running_) running_->stage = stage;
}

void StepLedger::Keep(int64_t step_id, std::vector<uint8_t> reply) {
  if (running_ && running_->step_id == step_id) running_.reset();
  if (step_id < 0) return;
  kept_bytes_ += reply.size();
  kept_.push_back({step_id, std::move(reply)});
  // The newest stays whatever its size; older ones go beyond either bound.
  while (kept_.size() > 1 &&
         (kept_.size() > kMaxKept || kept_bytes_ - kept_.back().reply.size() > kMaxKeptBytes)) {
    kept_bytes_ -= kept_.front().reply.size();
    kept_.pop_front();
  }
}

void StepLedger::Finish() { running_.reset(); }

StepRecall StepLedger::Recall(int64_t step_id, const std::deque<StepJob>& queue) const {
  StepRecall recall;
  const auto kept = std::find_if(kept_.rbegin(), kept_.rend(),
                                 [step_id](const Kept& k) { return k.step_id == step_id; });
  if (kept != kept_.rend()) {
    recall.kind = StepRecall::Kind::kAnswered;
    recall.reply = kept->reply;
    return recall;
  }
  if (running_ && running_->step_id == step_id) {
    recall.kind = StepRecall::Kind::kRunning;
    recall.request_id = running_->request_id;
    recall.stage = running_->stage;
    recall.received = running_->received;
    return recall;
  }
  for (size_t i = 0; i < queue.size(); ++i) {
    if (queue[i].command.step_id != step_id) continue;
    recall.kind = StepRecall::Kind::kQueued;
    recall.request_id = queue[i].command.request_id;
    recall.queue_position = static_cast<int32_t>(i);
    recall.received = queue[i].received;
    return recall;
  }
  return recall;  // kForgotten
}

}  // namespace far::server
