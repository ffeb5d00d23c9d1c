#include "view_pass.h"

#include "gl_program.h"

namespace far::internal {
namespace {

GLenum DepthInternalFormat(DepthFormat format) {
  switch (format) {
    case DepthFormat::kDepth16:
      return GL_DEPTH_COMPONENT16;
    case DepthFormat::kDepth24:
      return GL_DEPTH_COMPONENT24;
    case DepthFormat::kDepth32F:
      return GL_DEPTH_COMPONENT32F;
  }
  return GL_DEPTH_COMPONENT24;
}

GLuint Texture(GLenum format, const RasterFormat& raster) {
  GLuint t = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &t);
  glTextureStorage2D(t, 1, format, raster.width, raster.height);
  glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  return t;
}

GLuint DepthFramebuffer(GLuint depth) {
  GLuint fbo = 0;
  glCreateFramebuffers(1, &fbo);
  glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, depth, 0);
  glNamedFramebufferDrawBuffer(fbo, GL_NONE);
  return fbo;
}

}  // namespace

Result<std::unique_ptr<CullingPrograms>> CullingPrograms::Create() {
  std::unique_ptr<CullingPrograms> programs(new CullingPrograms());
  for (Shape shape : {Shape::kBox, Shape::kPrism, Shape::kTriangle}) {
    for (int r = 0; r < kNumRoles; ++r) {
      const auto role = static_cast<FragmentRole>(r);
      auto program = LinkProgram(ShaderSource(shape, role, true), ShaderSource(shape, role, false));
      if (!program.ok()) return program.error();
      programs->programs_[static_cast<size_t>(shape)][static_cast<size_t>(r)] = *program;
    }
  }
  return programs;
}

CullingPrograms::~CullingPrograms() {
  for (auto& shape : programs_) {
    for (GLuint program : shape) glDeleteProgram(program);
  }
}

Result<std::unique_ptr<CullTargets>> CullTargets::Create(const RasterFormat& raster) {
  std::unique_ptr<CullTargets> t(new CullTargets());
  t->id_texture = Texture(GL_R32UI, raster);
  t->depth_nearest = Texture(DepthInternalFormat(raster.depth), raster);
  t->depth_other = Texture(DepthInternalFormat(raster.depth), raster);
  glCreateFramebuffers(1, &t->fbo_id);
  glNamedFramebufferTexture(t->fbo_id, GL_COLOR_ATTACHMENT0, t->id_texture, 0);
  glNamedFramebufferTexture(t->fbo_id, GL_DEPTH_ATTACHMENT, t->depth_nearest, 0);
  t->fbo_other = DepthFramebuffer(t->depth_other);
  t->fbo_nearest_only = DepthFramebuffer(t->depth_nearest);
  for (GLuint fbo : {t->fbo_id, t->fbo_other, t->fbo_nearest_only}) {
    if (glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      return MakeError(ErrorCode::kInternal, "culling framebuffer is incomplete");
    }
  }
  glCreateBuffers(1, &t->flag_buffer);
  return t;
}

CullTargets::~CullTargets() {
  GLuint textures[] = {id_texture, depth_nearest, depth_other};
  glDeleteTextures(3, textures);
  GLuint fbos[] = {fbo_id, fbo_other, fbo_nearest_only};
  glDeleteFramebuffers(3, fbos);
  glDeleteBuffers(1, &flag_buffer);
  if (!queries.empty()) glDeleteQueries(static_cast<GLsizei>(queries.size()), queries.data());
}

void ViewPass::CullFaces(GLenum face) const {
  const bool closed = view_.sets.empty() || view_.sets[0] != PieceSet::kTriangles;
  if (closed) {
    glEnable(GL_CULL_FACE);
    glCullFace(face);
  } else {
    glDisable(GL_CULL_FACE);
  }
}

GLuint ViewPass::UseProgram(Shape shape, FragmentRole role) const {
  const GLuint program = programs_.get(shape, role);
  glUseProgram(program);
  glUniform1i(glGetUniformLocation(program, "triangles_per_primitive"),
              view_.triangles_per_primitive);
  return program;
}

bool ViewPass::DrawAll(FragmentRole role) {
  for (PieceSet set : view_.sets) {
    UseProgram(ShapeOf(set), role);
    if (!pacer_.DrawCommands(pieces_, set, role, counters_)) return false;
  }
  return true;
}

void ViewPass::DrawPrimitive(const ViewObject& object, int local, FragmentRole role) {
  for (PieceSet set : view_.sets) {
    UseProgram(ShapeOf(set), role);
    auto [first, count] = pieces_.PrimitiveRange(set, object, view_.triangles_per_primitive, local);
    pieces_.Draw(set, first, count, counters_);
    pacer_.NoteDrawn(pieces_, set, role, first, count);
  }
}

bool ViewPass::DrawObject(const ViewObject& object, FragmentRole role) {
  for (PieceSet set : view_.sets) {
    UseProgram(ShapeOf(set), role);
    auto [first, count] = pieces_.PrimitiveRange(set, object, 0, 0);
    if (!pacer_.DrawRange(pieces_, set, role, first, count, counters_)) return false;
  }
  return true;
}

int ViewPass::PrimitivesOf(const ViewObject& object) const {
  if (view_.triangles_per_primitive <= 0) return 1;
  const auto k = static_cast<uint32_t>(view_.triangles_per_primitive);
  return static_cast<int>((object.num_triangles + k - 1) / k);
}

}  // namespace far::internal
