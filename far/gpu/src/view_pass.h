#pragma once

#include <array>
#include <memory>
#include <optional>
#include <vector>

#include "culling_shaders.h"
#include "draw_pacer.h"
#include "piece_buffers.h"
#include <epoxy/gl.h>

#include "far/base/result.h"
#include "far/gpu/culling_renderer.h"

namespace far::internal {

/// The compiled culling programs: one per piece shape and fragment role.
class CullingPrograms {
 public:
  /// Compiles every program. Errors: kInternal with the driver's log.
  static Result<std::unique_ptr<CullingPrograms>> Create();
  ~CullingPrograms();
  GLuint get(Shape shape, FragmentRole role) const {
    return programs_[static_cast<size_t>(shape)][static_cast<size_t>(role)];
  }

 private:
  CullingPrograms() = default;
  std::array<std::array<GLuint, kNumRoles>, kNumShapes> programs_{};
};

/// What the visibility mechanisms render into, sized for one raster: the object-id buffer with
/// the nearest depth, the depth of the nearest other object, the flag buffer of the ID-buffer
/// mechanism and the occlusion queries.
class CullTargets {
 public:
  /// Errors: kInternal when a framebuffer is incomplete.
  static Result<std::unique_ptr<CullTargets>> Create(const RasterFormat& raster);
  ~CullTargets();

  GLuint id_texture = 0, depth_nearest = 0, depth_other = 0;
  GLuint fbo_id = 0;            ///< id + nearest depth
  GLuint fbo_other = 0;         ///< depth of the nearest other group
  GLuint fbo_nearest_only = 0;  ///< nearest depth alone (queries, flag pass)
  GLuint flag_buffer = 0;
  std::vector<GLuint> queries;  ///< one per primitive, grown on demand

 private:
  CullTargets() = default;
};

/// One axis view being rendered: draws the view's pieces with the program of a role, with the
/// face culling the pieces call for, in batches paced by a DrawPacer. What both mechanisms
/// draw with. The drawing calls that return bool return false when the view must stop
/// (pacer().stopped() says why): the mechanism then returns no answer.
class ViewPass {
 public:
  ViewPass(const AxisView& view, PieceBuffers& pieces, const CullingPrograms& programs,
           DrawPacer& pacer, RenderCounters* counters)
      : view_(view), pieces_(pieces), programs_(programs), pacer_(pacer), counters_(counters) {}

  const AxisView& view() const { return view_; }
  RenderCounters* counters() { return counters_; }
  DrawPacer& pacer() { return pacer_; }

  /// Closed offsets take the nearest depth from front faces and test with back faces (the
  /// paper's face culling); bare triangles (CULLIDE) have no inside: both sides are drawn.
  void CullFaces(GLenum face) const;
  /// Binds the program of `shape` and `role` (and its sub-object size).
  GLuint UseProgram(Shape shape, FragmentRole role) const;
  /// Draws every piece of the view's objects with `role`, in batches.
  bool DrawAll(FragmentRole role);
  /// Draws the pieces of sub-object `local` of `object` (the whole object when k = 0).
  void DrawPrimitive(const ViewObject& object, int local, FragmentRole role);
  /// Draws every piece of `object`, in batches.
  bool DrawObject(const ViewObject& object, FragmentRole role);
  /// Primitives of `object` in this view: its sub-objects, or 1.
  int PrimitivesOf(const ViewObject& object) const;

 private:
  const AxisView& view_;
  PieceBuffers& pieces_;
  const CullingPrograms& programs_;
  DrawPacer& pacer_;
  RenderCounters* counters_;
};

/// The ID-buffer mechanism (a fixed number of passes per view, docs/culling.md). Returns, per
/// primitive, 1 if it is not fully visible against the other groups; nullopt when the view
/// stopped (pass.pacer().stopped()).
std::optional<std::vector<uint8_t>> CullWithIdBuffer(ViewPass& pass, const CullTargets& targets);

/// The paper's mechanism: two passes of per-primitive occlusion queries. Same result.
std::optional<std::vector<uint8_t>> CullWithOcclusionQueries(ViewPass& pass, CullTargets& targets);

}  // namespace far::internal
