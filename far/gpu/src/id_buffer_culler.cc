// The ID-buffer mechanism: a fixed number of draws per view, whatever the primitive count.
//  1. front faces of all pieces, depth test LESS, writing the group id: per pixel the nearest
//     depth and the group it belongs to;
//  2. front faces again, discarding fragments of that nearest group: per pixel the nearest
//     depth of any other group (ties between groups land here, so they count as overlap);
//  3. back faces, depth test GEQUAL: against the nearest depth where another group owns it,
//     against the second buffer where the primitive's own group does; a passing fragment flags
//     its primitive. A primitive never flagged is fully visible against the other groups:
//     the set both occlusion-query passes prune (tests prove both give the same PCS).
// Each pass is drawn in batches (ViewPass::DrawAll); a view that must stop between two of them
// returns no answer.

#include <optional>
#include <vector>

#include "view_pass.h"

namespace far::internal {

std::optional<std::vector<uint8_t>> CullWithIdBuffer(ViewPass& pass, const CullTargets& targets) {
  const AxisView& view = pass.view();
  const GLfloat far_depth = 1.f;
  // Pass 1: nearest front face per pixel and the group it belongs to. Depth writes on before
  // clearing: glClearBuffer obeys the depth mask, and the previous view ended with it off (a
  // stale depth buffer would hide primitives).
  glBindFramebuffer(GL_FRAMEBUFFER, targets.fbo_id);
  glDepthMask(GL_TRUE);
  const GLuint zero_id[4] = {0, 0, 0, 0};
  glClearBufferuiv(GL_COLOR, 0, zero_id);
  glClearBufferfv(GL_DEPTH, 0, &far_depth);
  glDepthFunc(GL_LESS);
  pass.CullFaces(GL_BACK);
  if (!pass.DrawAll(FragmentRole::kWriteId)) return std::nullopt;
  // Pass 2: nearest front face of any other group.
  glBindFramebuffer(GL_FRAMEBUFFER, targets.fbo_other);
  glClearBufferfv(GL_DEPTH, 0, &far_depth);
  glBindTextureUnit(0, targets.id_texture);
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
  if (!pass.DrawAll(FragmentRole::kOtherDepth)) return std::nullopt;
  // Pass 3: back faces at or behind another group's nearest front face flag their primitive.
  std::vector<uint32_t> flags(static_cast<size_t>(view.num_primitives) + 1, 0);
  glNamedBufferData(targets.flag_buffer, static_cast<GLsizeiptr>(flags.size() * sizeof(uint32_t)),
                    flags.data(), GL_STREAM_READ);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, targets.flag_buffer);
  glDepthMask(GL_FALSE);
  glDepthFunc(GL_GEQUAL);
  pass.CullFaces(GL_FRONT);
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
  for (bool against_nearest : {true, false}) {
    glBindFramebuffer(GL_FRAMEBUFFER,
                      against_nearest ? targets.fbo_nearest_only : targets.fbo_other);
    for (PieceSet set : view.sets) {
      const GLuint program = pass.UseProgram(ShapeOf(set), FragmentRole::kFlag);
      glUniform1i(glGetUniformLocation(program, "against_nearest"), against_nearest ? 1 : 0);
    }
    if (!pass.DrawAll(FragmentRole::kFlag)) return std::nullopt;
  }
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glGetNamedBufferSubData(targets.flag_buffer, 0,
                          static_cast<GLsizeiptr>(flags.size() * sizeof(uint32_t)), flags.data());
  std::vector<uint8_t> stays(static_cast<size_t>(view.num_primitives), 0);
  for (size_t i = 0; i < stays.size(); ++i) stays[i] = flags[i] != 0 && view.alive[i] != 0;
  return stays;
}

}  // namespace far::internal
