// The paper's mechanism: one occlusion query per primitive and pass. Objects are drawn one by
// one, forward then in reverse order; before an object's front faces go into the depth buffer,
// each of its live primitives' back faces is queried against the objects drawn so far (depth
// func GEQUAL, depth writes off). Zero samples: fully visible in that pass. A primitive fully
// visible in both passes is pruned; the reverse pass queries only those visible in the first.

#include <vector>

#include "view_pass.h"

namespace far::internal {
namespace {

// Mesa 22.3 llvmpipe over-counts some results at 1536^2 and up unless flushed at least every
// 200 queries (docs/culling.md).
constexpr int kQueriesPerFlush = 128;

// Queries the live primitives of `object` (skipping those not visible in the forward pass when
// `forward_visible` is given); marks them in `queried`.
void QueryPrimitives(ViewPass& pass, const ViewObject& object, std::vector<GLuint>& queries,
                     const std::vector<uint8_t>* forward_visible, std::vector<uint8_t>& queried,
                     int& since_flush) {
  const AxisView& view = pass.view();
  glDepthMask(GL_FALSE);
  glDepthFunc(GL_GEQUAL);
  pass.CullFaces(GL_FRONT);
  for (int local = 0; local < pass.PrimitivesOf(object); ++local) {
    const uint32_t primitive = object.first_primitive + static_cast<uint32_t>(local);
    if (!view.alive[primitive]) continue;
    if (forward_visible != nullptr && !(*forward_visible)[primitive]) continue;
    glBeginQuery(GL_SAMPLES_PASSED, queries[primitive]);
    pass.DrawPrimitive(object, local, FragmentRole::kDepthOnly);
    glEndQuery(GL_SAMPLES_PASSED);
    queried[primitive] = 1;
    pass.counters()->queries++;
    if (++since_flush == kQueriesPerFlush) {
      glFlush();
      since_flush = 0;
    }
  }
}

// One pass over the view's objects in `order`; returns per primitive 1 when queried and fully
// visible, 0 otherwise; `stays` gets the primitives that were not.
std::vector<uint8_t> RunPass(ViewPass& pass, CullTargets& targets, bool reverse,
                             const std::vector<uint8_t>* forward_visible,
                             std::vector<uint8_t>& stays) {
  const AxisView& view = pass.view();
  glBindFramebuffer(GL_FRAMEBUFFER, targets.fbo_nearest_only);
  glDepthMask(GL_TRUE);  // glClearBuffer obeys the depth mask
  const GLfloat far_depth = 1.f;
  glClearBufferfv(GL_DEPTH, 0, &far_depth);
  std::vector<uint8_t> queried(stays.size(), 0);
  int since_flush = 0;
  const size_t n = view.objects.size();
  for (size_t step = 0; step < n; ++step) {
    const ViewObject& object = view.objects[reverse ? n - 1 - step : step];
    QueryPrimitives(pass, object, targets.queries, forward_visible, queried, since_flush);
    // Then the object's front faces go into the depth buffer.
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LEQUAL);
    pass.CullFaces(GL_BACK);
    pass.DrawObject(object, FragmentRole::kDepthOnly);
  }
  // Zero samples passed: fully visible in this pass.
  std::vector<uint8_t> visible(stays.size(), 0);
  for (size_t p = 0; p < stays.size(); ++p) {
    if (!queried[p]) continue;
    GLuint samples = 0;
    glGetQueryObjectuiv(targets.queries[p], GL_QUERY_RESULT, &samples);
    visible[p] = samples == 0;
    if (samples != 0) stays[p] = 1;
  }
  return visible;
}

}  // namespace

std::vector<uint8_t> CullWithOcclusionQueries(ViewPass& pass, CullTargets& targets) {
  const size_t primitives = static_cast<size_t>(pass.view().num_primitives);
  if (targets.queries.size() < primitives) {
    const size_t old = targets.queries.size();
    targets.queries.resize(primitives);
    glGenQueries(static_cast<GLsizei>(primitives - old), targets.queries.data() + old);
  }
  std::vector<uint8_t> stays(primitives, 0);
  const std::vector<uint8_t> forward_visible =
      RunPass(pass, targets, /*reverse=*/false, nullptr, stays);
  RunPass(pass, targets, /*reverse=*/true, &forward_visible, stays);
  return stays;
}

}  // namespace far::internal
