#include "draw_pacer.h"

#include <algorithm>
#include <cmath>

#include <epoxy/gl.h>

namespace far::internal {
namespace {

double MsSince(DrawPacer::Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(DrawPacer::Clock::now() - start).count();
}

}  // namespace

void BatchCosts::Record(PieceSet set, FragmentRole role, uint64_t instances, double ms) {
  if (instances == 0) return;
  double& known = ms_[static_cast<size_t>(set)][static_cast<size_t>(role)];
  const double measured = ms / static_cast<double>(instances);
  known = known < 0 || measured > known ? measured : 0.5 * (known + measured);
}

uint64_t DrawPacer::Budget(PieceSet set, FragmentRole role) const {
  const double per_instance = costs_.ms_per_instance(set, role);
  if (batch_ms_ <= 0) return 1;
  const uint64_t last = last_batch_[static_cast<size_t>(set)][static_cast<size_t>(role)];
  // Not measured yet (no pause has been wanted): a few at first, then growing.
  if (per_instance < 0) return last == 0 ? kFirstBatch : kGrowth * last;
  const uint64_t by_cost =
      per_instance == 0
          ? UINT32_MAX
          : static_cast<uint64_t>(std::clamp(batch_ms_ / per_instance, 1.0, double{UINT32_MAX}));
  return last == 0 ? by_cost : std::min(by_cost, kGrowth * last);
}

bool DrawPacer::DrawCommands(PieceBuffers& pieces, PieceSet set, FragmentRole role,
                             RenderCounters* counters) {
  const size_t commands = pieces.view_commands(set);
  size_t next = 0;
  uint64_t done_in_command = 0;  // instances of command `next` already drawn
  while (next < commands) {
    const Clock::time_point start = Clock::now();
    const uint64_t budget = Budget(set, role);
    const auto [first, count] = pieces.ViewCommand(set, next);
    uint64_t drawn = 0;
    if (done_in_command > 0 || count > budget) {
      // Part of one command (the batch is smaller than it, or its start was drawn).
      drawn = std::min(budget, count - done_in_command);
      pieces.Draw(set, first + done_in_command, drawn, counters);
      done_in_command += drawn;
      if (done_in_command == count) {
        ++next;
        done_in_command = 0;
      }
    } else {
      // Whole commands, as many as the budget holds (the first always fits).
      size_t end = next;
      while (end < commands && drawn + pieces.ViewCommand(set, end).second <= budget)
        drawn += pieces.ViewCommand(set, end++).second;
      pieces.DrawViewCommands(set, next, end, counters);
      next = end;
    }
    if (!AfterBatch(set, role, drawn, start, next == commands)) return false;
  }
  return true;
}

bool DrawPacer::DrawRange(PieceBuffers& pieces, PieceSet set, FragmentRole role, uint64_t first,
                          uint64_t count, RenderCounters* counters) {
  for (uint64_t done = 0; done < count;) {
    const Clock::time_point start = Clock::now();
    const uint64_t drawn = std::min(Budget(set, role), count - done);
    pieces.Draw(set, first + done, drawn, counters);
    done += drawn;
    if (!AfterBatch(set, role, drawn, start, done == count)) return false;
  }
  return true;
}

bool DrawPacer::AfterBatch(PieceSet set, FragmentRole role, uint64_t instances,
                           Clock::time_point start, bool last) {
  last_batch_[static_cast<size_t>(set)][static_cast<size_t>(role)] = instances;
  // A pass small enough, in a view that has been short so far: no pause. Its work is finished
  // by the next pause or by the view's read-back; a pause per pass would cost a GPU a round
  // trip each, for nothing.
  const double per_instance = costs_.ms_per_instance(set, role);
  const double predicted = per_instance < 0 ? batch_ms_ : per_instance * instances;
  if (last && unfinished_ms_ + predicted < batch_ms_ / 4 && MsSince(since_pause_) < batch_ms_ / 4) {
    unfinished_ms_ += predicted;
    return true;
  }
  // Nothing to pause for (the step cannot stop, no thread waits for the GL lock): the work
  // goes on unfinished, as one long batch.
  if (!PauseWantedNow()) return true;
  glFinish();
  // The batch's GL work (with what was left unfinished before it: counted with it).
  costs_.Record(set, role, instances, MsSince(start));
  return Pause();
}

bool DrawPacer::MaybePause() {
  if (MsSince(since_pause_) < batch_ms_ || !PauseWantedNow()) return false;
  glFinish();
  Pause();
  return true;
}

bool DrawPacer::Pause() {
  ++pauses_;
  if (between_) stopped_ = between_();
  since_pause_ = Clock::now();
  unfinished_ms_ = 0;
  return stopped_ == StopReason::kNone;
}

}  // namespace far::internal
