#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "culling_shaders.h"
#include "piece_footprint.h"
#include <epoxy/gl.h>

#include "far/gpu/culling_renderer.h"

namespace far::internal {

class DrawPacer;

/// The GPU instances of the four piece sets: per set a CPU copy per slot and one GL buffer with
/// the slots laid out in order, re-uploaded only where a slot changed. Draws whole views with
/// multi-draw-indirect calls over the view's commands (a batch of them at a time), or one
/// primitive's instances at a time. GL thread only.
class PieceBuffers {
 public:
  /// glMultiDrawElementsIndirect's command layout.
  struct DrawCommand {
    GLuint count;
    GLuint instance_count;
    GLuint first_index;
    GLint base_vertex;
    GLuint base_instance;
  };
  /// The most instances one view command draws: longer runs are cut, so that a view can be
  /// drawn in batches of whole commands (draw_pacer.h).
  static constexpr uint64_t kMaxCommandInstances = 4096;

  /// Makes the buffers, vertex layouts and corner index lists. @pre a GL context is current.
  PieceBuffers();
  ~PieceBuffers();
  PieceBuffers(const PieceBuffers&) = delete;
  PieceBuffers& operator=(const PieceBuffers&) = delete;

  void SetPieces(PieceSet set, uint32_t slot, std::vector<PieceInstance> pieces);
  void RemoveSlot(uint32_t slot);
  /// The largest slot number in use, plus one.
  size_t num_slots() const;

  /// Uploads a set's changed slots: only changed bytes when no slot changed size. In parts of
  /// a few MiB, with `pacer`'s pauses between them once it has taken long (a first upload of
  /// two million triangles' pieces is 112 MB). False when the pacer said stop: what is left
  /// is uploaded by the next Sync.
  bool Sync(PieceSet set, DrawPacer& pacer, RenderCounters* counters);
  /// Prepares the indirect commands of a view: per object of the view, its instances in `set`,
  /// only of the primitives still alive (one command per run of live sub-objects), so that a
  /// pass draws only those with one call.
  void PrepareViewDraws(PieceSet set, std::span<const ViewObject> objects,
                        std::span<const uint8_t> alive, int triangles_per_primitive,
                        int64_t* bytes);
  /// The view's draw commands of `set` (after PrepareViewDraws): runs of instances, each at
  /// most kMaxCommandInstances long.
  size_t view_commands(PieceSet set) const { return store(set).commands.size(); }
  /// Command `i` of the view's `set`: its first instance and its instance count.
  std::pair<uint64_t, uint64_t> ViewCommand(PieceSet set, size_t i) const;
  /// Draws the view's commands [begin, end) of `set` with one call.
  void DrawViewCommands(PieceSet set, size_t begin, size_t end, RenderCounters* counters);
  /// Draws instances [first, first + count) of a set.
  void Draw(PieceSet set, uint64_t first, uint64_t count, RenderCounters* counters);
  /// The summed footprint of instances [first, first + count) of a set, all of one slot (a view
  /// command, or part of one).
  PieceFootprint Footprint(PieceSet set, uint64_t first, uint64_t count) const;
  /// The instance range of sub-object `local` of `object` (the whole object when k = 0).
  std::pair<uint64_t, uint64_t> PrimitiveRange(PieceSet set, const ViewObject& object,
                                               int triangles_per_primitive, int local) const;

 private:
  struct Store {
    std::vector<std::vector<PieceInstance>> slots;
    // Per slot, the footprints of its first j * kFootprintBlock instances summed: a run's sum
    // from two of them and at most 2 kFootprintBlock pieces' own (1.5 bytes per instance).
    std::vector<std::vector<PieceFootprint>> footprint_sums;
    std::vector<uint64_t> first;  // first instance of each slot in the GL buffer
    std::vector<uint8_t> dirty;
    bool layout_changed = true;
    GLuint buffer = 0, vao = 0;
    uint64_t total = 0;
    GLuint indirect_buffer = 0;         // this view's draw commands
    std::vector<DrawCommand> commands;  // the same, on the CPU
  };
  static constexpr uint64_t kFootprintBlock = 16;
  // The footprints of slot `slot`'s first `count` instances of `set`, summed.
  PieceFootprint FootprintPrefix(PieceSet set, size_t slot, uint64_t count) const;

  Store& store(PieceSet set) { return stores_[static_cast<size_t>(set)]; }
  const Store& store(PieceSet set) const { return stores_[static_cast<size_t>(set)]; }

  std::array<Store, kNumPieceSets> stores_;
  std::array<GLuint, kNumShapes> index_buffers_{};  // per shape: CornerIndices
};

}  // namespace far::internal
