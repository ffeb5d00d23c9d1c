#include "draw_pacer.h"

#include <algorithm>
#include <cmath>

#include <epoxy/gl.h>

namespace far::internal {
namespace {

double MsSince(DrawPacer::Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(DrawPacer::Clock::now() - start).count();
}

// A dearer measurement counts at once, a cheaper one half.
void Blend(double& known, double measured) {
  known = known < 0 || measured > known ? measured : 0.5 * (known + measured);
}

}  // namespace

void BatchCosts::Record(PieceSet set, FragmentRole role, uint64_t instances, double ms) {
  if (instances == 0) return;
  Blend(ms_[static_cast<size_t>(set)][static_cast<size_t>(role)],
        ms / static_cast<double>(instances));
}

void BatchCosts::RecordFragments(FragmentRole role, uint64_t instances, uint64_t fragments,
                                 double ms) {
  if (instances == 0) return;
  const double equivalent =
      static_cast<double>(fragments) + kInstanceFragments * static_cast<double>(instances);
  Blend(ms_per_fragment_[static_cast<size_t>(role)], ms / equivalent);
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

bool DrawPacer::BoundsFill(FragmentRole role) const {
  return fill_.fragment_query != 0 && costs_.ms_per_fragment(role) >= 0 && batch_ms_ > 0;
}

double DrawPacer::FillMs(FragmentRole role, const PieceFootprint& footprint, uint64_t count) const {
  if (!BoundsFill(role)) return 0;
  return costs_.ms_per_fragment(role) * fill_.scale.Pixels(footprint, count);
}

uint64_t DrawPacer::WithinFill(const PieceBuffers& pieces, PieceSet set, FragmentRole role,
                               uint64_t first, uint64_t count) const {
  if (!BoundsFill(role) || !TooMuchFill(role, pieces.Footprint(set, first, count), count))
    return count;
  // The bound grows with the instances: the most that keep within it, by bisection.
  uint64_t fits = 1, over = count;
  while (over - fits > 1) {
    const uint64_t mid = fits + (over - fits) / 2;
    (TooMuchFill(role, pieces.Footprint(set, first, mid), mid) ? over : fits) = mid;
  }
  return fits;
}

void DrawPacer::BeginBatch() {
  if (fill_.fragment_query == 0 || !PauseWantedNow()) return;
  glBeginQuery(GL_FRAGMENT_SHADER_INVOCATIONS_ARB, fill_.fragment_query);
  counting_fragments_ = true;
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
    BeginBatch();
    // (Footprints are summed only where the fill is bounded: not before its cost is measured.)
    const bool bounded = BoundsFill(role);
    if (done_in_command > 0 || count > budget ||
        (bounded && TooMuchFill(role, pieces.Footprint(set, first, count), count))) {
      // Part of one command (the batch is smaller than it, or its start was drawn).
      drawn = WithinFill(pieces, set, role, first + done_in_command,
                         std::min(budget, count - done_in_command));
      pieces.Draw(set, first + done_in_command, drawn, counters);
      done_in_command += drawn;
      if (done_in_command == count) {
        ++next;
        done_in_command = 0;
      }
    } else {
      // Whole commands, as many as the budget and the fill bound hold (the first always fits).
      size_t end = next;
      PieceFootprint footprint;
      while (end < commands) {
        const auto [at, n] = pieces.ViewCommand(set, end);
        PieceFootprint with = footprint;
        if (bounded) with += pieces.Footprint(set, at, n);
        if (end > next && (drawn + n > budget || (bounded && TooMuchFill(role, with, drawn + n))))
          break;
        footprint = with;
        drawn += n;
        ++end;
      }
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
    const uint64_t drawn =
        WithinFill(pieces, set, role, first + done, std::min(Budget(set, role), count - done));
    BeginBatch();
    pieces.Draw(set, first + done, drawn, counters);
    done += drawn;
    if (!AfterBatch(set, role, drawn, start, done == count)) return false;
  }
  return true;
}

bool DrawPacer::AfterBatch(PieceSet set, FragmentRole role, uint64_t instances,
                           Clock::time_point start, bool last) {
  last_batch_[static_cast<size_t>(set)][static_cast<size_t>(role)] = instances;
  const bool counted = counting_fragments_;
  if (counted) glEndQuery(GL_FRAGMENT_SHADER_INVOCATIONS_ARB);
  counting_fragments_ = false;
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
  const double ms = MsSince(start);
  costs_.Record(set, role, instances, ms);
  if (counted) {
    GLuint64 fragments = 0;  // finished: the result is there
    glGetQueryObjectui64v(fill_.fragment_query, GL_QUERY_RESULT, &fragments);
    costs_.RecordFragments(role, instances, fragments, ms);
  }
  return Pause();
}

void DrawPacer::NoteDrawn(const PieceBuffers& pieces, PieceSet set, FragmentRole role,
                          uint64_t first, uint64_t count) {
  const double per_instance = std::max(costs_.ms_per_instance(set, role), 0.0);
  const double fill_ms =
      BoundsFill(role) ? FillMs(role, pieces.Footprint(set, first, count), count) : 0;
  unfinished_ms_ += std::max(per_instance * static_cast<double>(count), fill_ms / kFillSlack);
}

bool DrawPacer::MaybePause() {
  const bool long_enough = MsSince(since_pause_) >= batch_ms_ || unfinished_ms_ >= batch_ms_;
  if (!long_enough || !PauseWantedNow()) return false;
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
