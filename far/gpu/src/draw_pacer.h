#pragma once

// A view's draws in batches of bounded GL work, with a pause between batches: so that a long
// view (hundreds of thousands of pieces, a large viewport: seconds on llvmpipe) notices a
// step's deadline within a batch, and hands the GL lock to other threads' views between its
// batches instead of holding it for the whole view (docs/daemon.md, "Sessions and the GL
// driver"). Private to far::gpu.

#include <array>
#include <chrono>
#include <cstdint>

#include "culling_shaders.h"
#include "piece_buffers.h"
#include "piece_footprint.h"

#include "far/base/step_control.h"
#include "far/gpu/culling_renderer.h"

namespace far::internal {

/// What one batch of each piece set and role cost: milliseconds of GL work per instance, and
/// per fragment of each role, as measured (a renderer keeps them from view to view). Batches are
/// sized from them. A dearer batch counts at once, a cheaper one half (so that one slow batch
/// shortens the next at once).
class BatchCosts {
 public:
  /// Fragment shader invocations one instance is counted as, beside its own fragments: its
  /// vertex and setup work, so that a batch of pieces hidden by the depth test (few fragments)
  /// does not make every fragment look dear.
  static constexpr double kInstanceFragments = 64;

  /// ms per instance of `set` drawn with `role`, or a negative number when not yet measured.
  double ms_per_instance(PieceSet set, FragmentRole role) const {
    return ms_[static_cast<size_t>(set)][static_cast<size_t>(role)];
  }
  /// Records a batch of `instances` that took `ms`.
  void Record(PieceSet set, FragmentRole role, uint64_t instances, double ms);

  /// ms per fragment drawn with `role` (see kInstanceFragments), negative when not yet measured.
  double ms_per_fragment(FragmentRole role) const {
    return ms_per_fragment_[static_cast<size_t>(role)];
  }
  /// Records a batch of `instances` that ran `fragments` fragment shader invocations in `ms`.
  void RecordFragments(FragmentRole role, uint64_t instances, uint64_t fragments, double ms);

 private:
  std::array<std::array<double, kNumRoles>, kNumPieceSets> ms_ = [] {
    std::array<std::array<double, kNumRoles>, kNumPieceSets> all;
    for (auto& set : all) set.fill(-1.0);
    return all;
  }();
  std::array<double, kNumRoles> ms_per_fragment_ = [] {
    std::array<double, kNumRoles> all;
    all.fill(-1.0);
    return all;
  }();
};

/// What bounds a batch's fill before it is drawn: the view's scale (piece_footprint.h) and a
/// GL_FRAGMENT_SHADER_INVOCATIONS query that measures what a fragment costs (0: the context has
/// no pipeline statistics, and batches are sized on their instances alone).
struct FillBound {
  ViewScale scale;
  GLuint fragment_query = 0;
};

/// Draws one view's passes in batches and pauses between them. A pause finishes the GL work
/// drawn so far (glFinish), measures it and calls the view's BetweenBatches hook, which may
/// hand the GL lock over and says whether the view must stop. A batch is sized to take about
/// `batch_ms`; a view small enough to take less than a fraction of that in all is drawn as it
/// was before, one call per pass and no pause (its read-back waits for it anyway).
class DrawPacer {
 public:
  using Clock = std::chrono::steady_clock;
  /// The GL work one batch aims at, by default.
  static constexpr double kDefaultBatchMs = 8;
  /// Instances of a batch whose cost is not known yet: few, as one piece may cover the whole
  /// viewport (512 such pieces at 2048^2 took seconds on llvmpipe).
  static constexpr uint64_t kFirstBatch = 16;
  /// A batch draws at most this many times the instances of the one before it in the view (of
  /// its set and role): pieces of one view differ in cost, and a batch sized on cheap ones
  /// should not meet a long run of dear ones at full size.
  static constexpr uint64_t kGrowth = 4;
  /// A batch's pieces may cover at most this many batches' time of fragments, bounded by their
  /// footprints at the measured cost per fragment. The cost per instance sizes batches on the
  /// pieces drawn so far, and pieces seen edge-on cost little: a stack of large triangles seen
  /// edge-on then face-on cost 60x more per piece within one view (one batch held the GL lock
  /// for 0.4-0.9 s on llvmpipe). The footprint bounds what is about to be drawn. It is loose by
  /// design (a piece seen edge-on is bounded as if face-on), hence a few batches' time, so that
  /// it shortens only batches that may be far dearer than the cost per instance says.
  static constexpr double kFillSlack = 4;

  /// All aliased: must outlive *this. `between` may be empty (no pauses but the measuring).
  /// `batch_ms` <= 0: one instance per batch, each followed by a pause (for tests). `wanted`
  /// may be empty (every batch boundary pauses as above); else a boundary pauses only when it
  /// returns true, and until the cost is measured each batch draws kGrowth times the last.
  /// `fill`: see FillBound (default: batches sized on their instances alone).
  DrawPacer(BatchCosts& costs, const BetweenBatches& between, double batch_ms = kDefaultBatchMs,
            const PauseWanted& wanted = {}, const FillBound& fill = {})
      : costs_(costs), between_(between), batch_ms_(batch_ms), wanted_(wanted), fill_(fill) {}

  /// Draws the view's commands of `set` (PieceBuffers::PrepareViewDraws) with `role`'s program
  /// bound, in batches. False when the view must stop (stopped() says why).
  bool DrawCommands(PieceBuffers& pieces, PieceSet set, FragmentRole role,
                    RenderCounters* counters);
  /// Draws instances [first, first + count) of `set` in batches. False: stop.
  bool DrawRange(PieceBuffers& pieces, PieceSet set, FragmentRole role, uint64_t first,
                 uint64_t count, RenderCounters* counters);
  /// For work drawn outside the pacer (per-primitive occlusion queries): counts what instances
  /// [first, first + count) of `set` drawn with `role` may cost, as a batch of them would be
  /// judged (their cost per instance, their fill bound over kFillSlack).
  void NoteDrawn(const PieceBuffers& pieces, PieceSet set, FragmentRole role, uint64_t first,
                 uint64_t count);
  /// For work drawn outside the pacer: pauses when the GL work since the last pause may have
  /// taken a batch's time, judged by what NoteDrawn counted and by the CPU time spent issuing
  /// it. Returns whether it paused (the work is then finished); stopped() says whether to stop.
  bool MaybePause();
  /// The view's radius, once its data is uploaded (the pieces' uploads come first).
  void set_fill_radius(double radius) { fill_.scale.radius = radius; }
  /// Why the view must stop, or kNone.
  StopReason stopped() const { return stopped_; }
  /// How many pauses the view made.
  int pauses() const { return pauses_; }

 private:
  // The instances the next batch of (set, role) may draw.
  uint64_t Budget(PieceSet set, FragmentRole role) const;
  // The most of the `count` instances from `first` (at least one) whose fill is within bounds.
  uint64_t WithinFill(const PieceBuffers& pieces, PieceSet set, FragmentRole role, uint64_t first,
                      uint64_t count) const;
  // Whether batches of `role` are bounded by their fill: pipeline statistics, and the cost of
  // a fragment measured.
  bool BoundsFill(FragmentRole role) const;
  // What `footprint` of `count` pieces may cost with `role` by its fill bound, ms (0: unknown).
  double FillMs(FragmentRole role, const PieceFootprint& footprint, uint64_t count) const;
  // Whether `footprint` of `count` pieces may take longer than kFillSlack batches with `role`.
  bool TooMuchFill(FragmentRole role, const PieceFootprint& footprint, uint64_t count) const {
    return FillMs(role, footprint, count) > kFillSlack * batch_ms_;
  }
  // Starts counting the next batch's fragments (when its cost will be measured).
  void BeginBatch();
  // After a batch drawn since `start`; `last`: it ends the pass. False: stop.
  bool AfterBatch(PieceSet set, FragmentRole role, uint64_t instances, Clock::time_point start,
                  bool last);
  // Finishes the GL work, then the hook. False: stop.
  bool Pause();

  // Whether a pause is wanted now.
  bool PauseWantedNow() const { return !wanted_ || wanted_(); }

  BatchCosts& costs_;
  const BetweenBatches& between_;
  double batch_ms_;
  const PauseWanted& wanted_;
  FillBound fill_;
  bool counting_fragments_ = false;  // the fragment query runs for the current batch
  StopReason stopped_ = StopReason::kNone;
  int pauses_ = 0;
  Clock::time_point since_pause_ = Clock::now();
  double unfinished_ms_ = 0;  // predicted GL work drawn since the last pause
  // The instances of the last batch of each set and role in this view (0: none yet).
  std::array<std::array<uint64_t, kNumRoles>, kNumPieceSets> last_batch_{};
};

}  // namespace far::internal
