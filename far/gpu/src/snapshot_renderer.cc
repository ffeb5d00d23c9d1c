// RenderSnapshot: a shaded picture of a scene with its PCS and contact triangles coloured,
// drawn into a multisampled framebuffer of its own and read back. Used by far-snapshot.

#include "far/gpu/snapshot_renderer.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "gl_program.h"
#include <Eigen/Geometry>
#include <epoxy/gl.h>

namespace far {
namespace {

constexpr int kMinSize = 16;
constexpr int kMaxSize = 8192;
constexpr int kFloatsPerVertex = 9;  // position, normal, colour

// Flat Lambert shading, lit from `light` on both faces (open surfaces such as leaves show
// either side). Positions are relative to the scene's centre, so float keeps them precise.
constexpr const char* kVertexShader = R"(#version 450 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 color;
uniform mat4 view_projection;
uniform vec3 light;
out vec3 shaded;
void main() {
  gl_Position = view_projection * vec4(position, 1.0);
  shaded = color * (0.3 + 0.7 * abs(dot(normal, light)));
}
)";

constexpr const char* kFragmentShader = R"(#version 450 core
in vec3 shaded;
uniform float alpha;
out vec4 fragment;
void main() { fragment = vec4(shaded, alpha); }
)";

Result<void> CheckInput(std::span<const SnapshotObject> objects, const SnapshotOptions& options) {
  for (const int size : {options.width, options.height}) {
    if (size < kMinSize || size > kMaxSize) {
      return MakeError(ErrorCode::kInvalidArgument,
                       "snapshot size " + std::to_string(options.width) + "x" +
                           std::to_string(options.height) + " is outside [" +
                           std::to_string(kMinSize) + ", " + std::to_string(kMaxSize) + "]");
    }
  }
  for (size_t i = 0; i < objects.size(); ++i) {
    const SnapshotObject& object = objects[i];
    const std::string where = "snapshot object " + std::to_string(i) + ": ";
    if (object.mesh == nullptr) return MakeError(ErrorCode::kInvalidArgument, where + "no mesh");
    if (auto valid = ValidateMesh(*object.mesh); !valid) {
      return MakeError(valid.error().code, where + valid.error().message);
    }
    if (!object.marks.empty() && object.marks.size() != object.mesh->triangles.size()) {
      return MakeError(ErrorCode::kInvalidArgument,
                       where + std::to_string(object.marks.size()) + " marks for " +
                           std::to_string(object.mesh->triangles.size()) + " triangles");
    }
    if (auto valid = CheckPose(object.X_WO); !valid) {
      return MakeError(valid.error().code, where + valid.error().message);
    }
  }
  return {};
}

// Every vertex in the world frame, relative to `center`.
std::vector<Eigen::Vector3d> WorldVertices(std::span<const SnapshotObject> objects,
                                           const Eigen::Vector3d& center) {
  std::vector<Eigen::Vector3d> p_CV;
  for (const SnapshotObject& object : objects) {
    const Eigen::Isometry3d X_WO = NormalizedPose(object.X_WO).ToIsometry();
    for (const Eigen::Vector3d& p_MV : object.mesh->p_MV) p_CV.push_back(X_WO * p_MV - center);
  }
  return p_CV;
}

// The world-frame box around every vertex (a unit box at the origin when there are none).
Eigen::AlignedBox3d Bounds(std::span<const SnapshotObject> objects) {
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p_WV : WorldVertices(objects, Eigen::Vector3d::Zero())) {
    box.extend(p_WV);
  }
  if (box.isEmpty())
    box = Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1));
  return box;
}

// The triangles as vertices (three per triangle, flat normals), contact triangles last so
// that one draw call can repeat them; sets *num_contact_triangles.
std::vector<float> TriangleVertices(std::span<const SnapshotObject> objects,
                                    const Eigen::Vector3d& center, size_t* num_contact_triangles) {
  std::vector<float> plain, contact;
  for (const SnapshotObject& object : objects) {
    const Eigen::Isometry3d X_WO = NormalizedPose(object.X_WO).ToIsometry();
    const Mesh& mesh = *object.mesh;
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const TriangleMark mark = object.marks.empty() ? TriangleMark::kPlain : object.marks[t];
      std::vector<float>& out = mark == TriangleMark::kContact ? contact : plain;
      Eigen::Vector3d p[3];
      for (int k = 0; k < 3; ++k) p[k] = X_WO * mesh.p_MV[mesh.triangles[t][k]] - center;
      Eigen::Vector3d normal = (p[1] - p[0]).cross(p[2] - p[0]);
      // A degenerate triangle has no normal: a zero one shades it as the ambient part only.
      normal = normal.norm() > 0 ? Eigen::Vector3d(normal.normalized()) : Eigen::Vector3d::Zero();
      const Eigen::Vector3f color = MarkColor(mark);
      for (const Eigen::Vector3d& q : p) {
        out.insert(out.end(),
                   {static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()),
                    static_cast<float>(normal.x()), static_cast<float>(normal.y()),
                    static_cast<float>(normal.z()), color.x(), color.y(), color.z()});
      }
    }
  }
  *num_contact_triangles = contact.size() / (3 * kFloatsPerVertex);
  plain.insert(plain.end(), contact.begin(), contact.end());
  return plain;
}

// A perspective camera looking at the box's centre (the origin of the vertices) from above and
// to the side, z up, just far enough away that every vertex is in view. Depth is mapped to
// [0, 1] (glClipControl GL_ZERO_TO_ONE).
struct Camera {
  Eigen::Matrix4f view_projection;
  Eigen::Vector3f light;  ///< unit direction towards the light
};

// The camera's axes: `to_eye` points from the centre to the camera.
struct ViewAxes {
  Eigen::Vector3d to_eye, right, up;
};

ViewAxes ObliqueView() {
  const double azimuth = -55.0 * std::numbers::pi / 180, elevation = 28.0 * std::numbers::pi / 180;
  ViewAxes axes;
  axes.to_eye = Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                                std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
  axes.right = (-axes.to_eye).cross(Eigen::Vector3d::UnitZ()).normalized();
  axes.up = axes.right.cross(-axes.to_eye);
  return axes;
}

// The smallest distance from the centre at which every point of `p_CV` (relative to the
// centre) is inside the view of half-angles atan(tan_x), atan(tan_y), with a small margin.
double FittingDistance(const std::vector<Eigen::Vector3d>& p_CV, const ViewAxes& axes, double tan_x,
                       double tan_y, double radius) {
  double distance = 0;
  for (const Eigen::Vector3d& p : p_CV) {
    const double depth = p.dot(axes.to_eye);  // towards the camera
    distance = std::max({distance, depth + std::abs(p.dot(axes.right)) / tan_x,
                         depth + std::abs(p.dot(axes.up)) / tan_y});
  }
  // Never inside the box, and a margin of a few pixels around the scene.
  return std::max(1.06 * distance, 1.2 * radius);
}

Camera FitCamera(const std::vector<Eigen::Vector3d>& p_CV, double radius, double aspect) {
  radius = std::max(radius, 1e-9);
  const ViewAxes axes = ObliqueView();
  const double fov_y = 30.0 * std::numbers::pi / 180;
  const double tan_y = std::tan(fov_y / 2), tan_x = aspect * tan_y;
  const double distance = FittingDistance(p_CV, axes, tan_x, tan_y, radius);
  Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
  view.block<1, 3>(0, 0) = axes.right.transpose();
  view.block<1, 3>(1, 0) = axes.up.transpose();
  view.block<1, 3>(2, 0) = axes.to_eye.transpose();
  view.block<3, 1>(0, 3) = -view.block<3, 3>(0, 0) * (distance * axes.to_eye);
  const double near = std::max(distance - 1.1 * radius, 1e-3 * distance);
  const double far = distance + 1.1 * radius;
  Eigen::Matrix4d projection = Eigen::Matrix4d::Zero();
  projection(0, 0) = 1 / tan_x;
  projection(1, 1) = 1 / tan_y;
  projection(2, 2) = far / (near - far);
  projection(2, 3) = far * near / (near - far);
  projection(3, 2) = -1;
  // The light comes from the camera, a little from above and from the left.
  const Eigen::Vector3d light = (axes.to_eye + 0.5 * axes.up - 0.3 * axes.right).normalized();
  return {(projection * view).cast<float>(), light.cast<float>()};
}

// The GL objects of one snapshot, deleted on every path out. The state that other far
// renderers sharing the context set once (clip control) is put back.
struct SnapshotGl {
  GLuint renderbuffers[3] = {};  // multisampled colour, multisampled depth, resolved colour
  GLuint framebuffers[2] = {};   // drawn into, resolved into
  GLuint program = 0, vertex_array = 0, vertex_buffer = 0;
  GLint clip_origin = GL_LOWER_LEFT, clip_depth = GL_NEGATIVE_ONE_TO_ONE;

  SnapshotGl() {
    glGetIntegerv(GL_CLIP_ORIGIN, &clip_origin);
    glGetIntegerv(GL_CLIP_DEPTH_MODE, &clip_depth);
  }
  ~SnapshotGl() {
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glUseProgram(0);
    glBindVertexArray(0);
    glDeleteFramebuffers(2, framebuffers);
    glDeleteRenderbuffers(3, renderbuffers);
    glDeleteBuffers(1, &vertex_buffer);
    glDeleteVertexArrays(1, &vertex_array);
    if (program != 0) glDeleteProgram(program);
    glClipControl(static_cast<GLenum>(clip_origin), static_cast<GLenum>(clip_depth));
  }
  SnapshotGl(const SnapshotGl&) = delete;
  SnapshotGl& operator=(const SnapshotGl&) = delete;
};

// Framebuffers of width x height: one multisampled to draw into, one to resolve into.
Result<void> CreateTargets(SnapshotGl& gl, int width, int height, int samples) {
  GLint max_samples = 0;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  samples = std::clamp(samples, 0, max_samples);
  glCreateRenderbuffers(3, gl.renderbuffers);
  glNamedRenderbufferStorageMultisample(gl.renderbuffers[0], samples, GL_RGBA8, width, height);
  glNamedRenderbufferStorageMultisample(gl.renderbuffers[1], samples, GL_DEPTH_COMPONENT24, width,
                                        height);
  glNamedRenderbufferStorage(gl.renderbuffers[2], GL_RGBA8, width, height);
  glCreateFramebuffers(2, gl.framebuffers);
  glNamedFramebufferRenderbuffer(gl.framebuffers[0], GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                                 gl.renderbuffers[0]);
  glNamedFramebufferRenderbuffer(gl.framebuffers[0], GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                                 gl.renderbuffers[1]);
  glNamedFramebufferRenderbuffer(gl.framebuffers[1], GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                                 gl.renderbuffers[2]);
  for (GLuint framebuffer : gl.framebuffers) {
    if (glCheckNamedFramebufferStatus(framebuffer, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      return MakeError(ErrorCode::kInternal, "snapshot framebuffer of " + std::to_string(width) +
                                                 "x" + std::to_string(height) + " is incomplete");
    }
  }
  return internal::CheckGl("creating the snapshot framebuffers");
}

// Uploads the vertices and links the program.
Result<void> CreateGeometry(SnapshotGl& gl, const std::vector<float>& vertices) {
  auto program = internal::LinkProgram(kVertexShader, kFragmentShader);
  if (!program.ok()) return program.error();
  gl.program = *program;
  glCreateBuffers(1, &gl.vertex_buffer);
  glNamedBufferData(gl.vertex_buffer, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)),
                    vertices.empty() ? nullptr : vertices.data(), GL_STATIC_DRAW);
  glCreateVertexArrays(1, &gl.vertex_array);
  glVertexArrayVertexBuffer(gl.vertex_array, 0, gl.vertex_buffer, 0,
                            kFloatsPerVertex * sizeof(float));
  for (GLuint attribute = 0; attribute < 3; ++attribute) {
    glEnableVertexArrayAttrib(gl.vertex_array, attribute);
    glVertexArrayAttribFormat(gl.vertex_array, attribute, 3, GL_FLOAT, GL_FALSE,
                              3 * attribute * sizeof(float));
    glVertexArrayAttribBinding(gl.vertex_array, attribute, 0);
  }
  return internal::CheckGl("uploading the snapshot's triangles");
}

// Draws every triangle, then the hidden parts of the contact triangles (the last
// `num_contact` ones) faded over what hides them.
void Draw(const SnapshotGl& gl, const Camera& camera, size_t num_triangles, size_t num_contact,
          const SnapshotOptions& options) {
  glBindFramebuffer(GL_FRAMEBUFFER, gl.framebuffers[0]);
  glViewport(0, 0, options.width, options.height);
  glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDepthMask(GL_TRUE);
  const Eigen::Vector3f background = SnapshotBackground();
  const GLfloat clear_color[4] = {background.x(), background.y(), background.z(), 1.0f};
  const GLfloat clear_depth = 1.0f;
  glClearBufferfv(GL_COLOR, 0, clear_color);
  glClearBufferfv(GL_DEPTH, 0, &clear_depth);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glUseProgram(gl.program);
  glBindVertexArray(gl.vertex_array);
  glUniformMatrix4fv(glGetUniformLocation(gl.program, "view_projection"), 1, GL_FALSE,
                     camera.view_projection.data());
  glUniform3fv(glGetUniformLocation(gl.program, "light"), 1, camera.light.data());
  glUniform1f(glGetUniformLocation(gl.program, "alpha"), 1.0f);
  glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(3 * num_triangles));
  if (options.show_hidden_contacts && num_contact > 0) {
    glDepthFunc(GL_GREATER);  // only where something nearer was drawn
    glDepthMask(GL_FALSE);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glUniform1f(glGetUniformLocation(gl.program, "alpha"), 0.45f);
    glDrawArrays(GL_TRIANGLES, static_cast<GLint>(3 * (num_triangles - num_contact)),
                 static_cast<GLsizei>(3 * num_contact));
    glDisable(GL_BLEND);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LESS);
  }
}

// Resolves the multisampled picture and reads it back, top row first.
RgbImage ReadBack(const SnapshotGl& gl, int width, int height) {
  glBlitNamedFramebuffer(gl.framebuffers[0], gl.framebuffers[1], 0, 0, width, height, 0, 0, width,
                         height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  RgbImage image;
  image.width = width;
  image.height = height;
  const size_t row = static_cast<size_t>(width) * 3;
  std::vector<uint8_t> bottom_up(row * static_cast<size_t>(height));
  glBindFramebuffer(GL_READ_FRAMEBUFFER, gl.framebuffers[1]);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, bottom_up.data());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  image.rgb.resize(bottom_up.size());
  for (int y = 0; y < height; ++y) {
    std::copy_n(
        bottom_up.begin() + static_cast<std::ptrdiff_t>(row * static_cast<size_t>(y)), row,
        image.rgb.begin() + static_cast<std::ptrdiff_t>(row * static_cast<size_t>(height - 1 - y)));
  }
  return image;
}

}  // namespace

Eigen::Vector3f MarkColor(TriangleMark mark) {
  switch (mark) {
    case TriangleMark::kPlain:
      return {0.72f, 0.72f, 0.72f};
    case TriangleMark::kPcs:
      return {1.0f, 0.85f, 0.1f};
    case TriangleMark::kNear:
      return {1.0f, 0.5f, 0.05f};
    case TriangleMark::kContact:
      return {0.95f, 0.05f, 0.05f};
  }
  return {1.0f, 0.0f, 1.0f};
}

Eigen::Vector3f SnapshotBackground() { return {0.13f, 0.15f, 0.19f}; }

Result<RgbImage> RenderSnapshot(std::span<const SnapshotObject> objects,
                                const SnapshotOptions& options) {
  if (auto valid = CheckInput(objects, options); !valid) return valid.error();
  const Eigen::AlignedBox3d box = Bounds(objects);
  size_t num_contact = 0;
  const std::vector<float> vertices = TriangleVertices(objects, box.center(), &num_contact);
  const size_t num_triangles = vertices.size() / (3 * kFloatsPerVertex);
  SnapshotGl gl;
  if (auto made = CreateTargets(gl, options.width, options.height, options.samples); !made) {
    return made.error();
  }
  if (auto made = CreateGeometry(gl, vertices); !made) return made.error();
  const Camera camera =
      FitCamera(WorldVertices(objects, box.center()), 0.5 * box.diagonal().norm(),
                static_cast<double>(options.width) / static_cast<double>(options.height));
  Draw(gl, camera, num_triangles, num_contact, options);
  RgbImage image = ReadBack(gl, options.width, options.height);
  if (auto drawn = internal::CheckGl("drawing the snapshot"); !drawn) return drawn.error();
  return image;
}

}  // namespace far
