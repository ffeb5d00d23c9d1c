// The paper's mechanism: one occlusion query per primitive and pass. Objects are drawn one by
// one, forward then in reverse order; before an object's front faces go into the depth buffer,
// each of its live primitives' back faces is queried against the objects drawn so far (depth
// func GEQUAL, depth writes off). Zero samples: fully visible in that pass. A primitive fully
// visible in both passes is pruned; the reverse pass queries only those visible in the first.
// The queries go in groups with a pause between two when the view has run long (DrawPacer); the
// results of the queries a pause finished are read then, not all at the end.

#include <optional>
#include <vector>

#include "view_pass.h"

namespace far::internal {
namespace {

// Mesa 22.3 llvmpipe over-counts some results at 1536^2 and up unless flushed at least every
// 200 queries (docs/culling.md).
constexpr int kQueriesPerFlush = 128;

// The queries of one pass: issued and not yet read, and what was read.
struct PassQueries {
  std::vector<GLuint>& queries;   // one per primitive
  std::vector<uint32_t> pending;  // primitives queried, results not yet read
  std::vector<uint8_t> visible;   // per primitive: queried and fully visible
  std::vector<uint8_t>& stays;    // per primitive: found not fully visible (in any pass)
  int since_flush = 0;

  // Reads the pending queries' results (waits for them).
  void Read() {
    for (uint32_t p : pending) {
      GLuint samples = 0;
      glGetQueryObjectuiv(queries[p], GL_QUERY_RESULT, &samples);
      visible[p] = samples == 0;
      if (samples != 0) stays[p] = 1;
    }
    pending.clear();
  }
};

// Flushes every kQueriesPerFlush queries, and pauses when the queries drawn since the last
// pause may have taken a batch's time (the pause finishes them: their results are read at
// once). Judged after every query: 128 queries of large pieces at 2048^2 held the GL lock for
// 0.5 s on llvmpipe. False: the view must stop.
bool AfterQuery(ViewPass& pass, PassQueries& q) {
  if (++q.since_flush >= kQueriesPerFlush) {
    glFlush();
    q.since_flush = 0;
  }
  if (pass.pacer().MaybePause()) {
    q.Read();
    q.since_flush = 0;
  }
  return pass.pacer().stopped() == StopReason::kNone;
}

// Queries the live primitives of `object` (skipping those not visible in the forward pass when
// `forward_visible` is given). False: the view must stop.
bool QueryPrimitives(ViewPass& pass, const ViewObject& object,
                     const std::vector<uint8_t>* forward_visible, PassQueries& q) {
  const AxisView& view = pass.view();
  glDepthMask(GL_FALSE);
  glDepthFunc(GL_GEQUAL);
  pass.CullFaces(GL_FRONT);
  for (int local = 0; local < pass.PrimitivesOf(object); ++local) {
    const uint32_t primitive = object.first_primitive + static_cast<uint32_t>(local);
    if (!view.alive[primitive]) continue;
    if (forward_visible != nullptr && !(*forward_visible)[primitive]) continue;
    glBeginQuery(GL_SAMPLES_PASSED, q.queries[primitive]);
    pass.DrawPrimitive(object, local, FragmentRole::kDepthOnly);
    glEndQuery(GL_SAMPLES_PASSED);
    q.pending.push_back(primitive);
    pass.counters()->queries++;
    if (!AfterQuery(pass, q)) return false;
  }
  return true;
}

// One pass over the view's objects in `order`; returns per primitive 1 when queried and fully
// visible, 0 otherwise; `stays` gets the primitives that were not. nullopt: the view stopped.
std::optional<std::vector<uint8_t>> RunPass(ViewPass& pass, CullTargets& targets, bool reverse,
                                            const std::vector<uint8_t>* forward_visible,
                                            std::vector<uint8_t>& stays) {
  const AxisView& view = pass.view();
  glBindFramebuffer(GL_FRAMEBUFFER, targets.fbo_nearest_only);
  glDepthMask(GL_TRUE);  // glClearBuffer obeys the depth mask
  const GLfloat far_depth = 1.f;
  glClearBufferfv(GL_DEPTH, 0, &far_depth);
  PassQueries q{targets.queries, {}, std::vector<uint8_t>(stays.size(), 0), stays};
  const size_t n = view.objects.size();
  for (size_t step = 0; step < n; ++step) {
    const ViewObject& object = view.objects[reverse ? n - 1 - step : step];
    if (!QueryPrimitives(pass, object, forward_visible, q)) return std::nullopt;
    // Then the object's front faces go into the depth buffer.
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LEQUAL);
    pass.CullFaces(GL_BACK);
    if (!pass.DrawObject(object, FragmentRole::kDepthOnly)) return std::nullopt;
  }
  // Zero samples passed: fully visible in this pass.
  q.Read();
  return std::move(q.visible);
}

}  // namespace

std::optional<std::vector<uint8_t>> CullWithOcclusionQueries(ViewPass& pass, CullTargets& targets) {
  const size_t primitives = static_cast<size_t>(pass.view().num_primitives);
  if (targets.queries.size() < primitives) {
    const size_t old = targets.queries.size();
    targets.queries.resize(primitives);
    glGenQueries(static_cast<GLsizei>(primitives - old), targets.queries.data() + old);
  }
  std::vector<uint8_t> stays(primitives, 0);
  const auto forward_visible = RunPass(pass, targets, /*reverse=*/false, nullptr, stays);
  if (!forward_visible) return std::nullopt;
  if (!RunPass(pass, targets, /*reverse=*/true, &*forward_visible, stays)) return std::nullopt;
  return stays;
}

}  // namespace far::internal
