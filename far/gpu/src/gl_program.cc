#include "gl_program.h"

#include <vector>

namespace far::internal {
namespace {

std::string InfoLog(GLuint object, bool is_program) {
  GLint length = 0;
  is_program ? glGetProgramiv(object, GL_INFO_LOG_LENGTH, &length)
             : glGetShaderiv(object, GL_INFO_LOG_LENGTH, &length);
  std::vector<char> log(static_cast<size_t>(std::max(length, 1)));
  is_program ? glGetProgramInfoLog(object, length, nullptr, log.data())
             : glGetShaderInfoLog(object, length, nullptr, log.data());
  return std::string(log.data());
}

Result<GLuint> Compile(GLenum stage, const std::string& source) {
  GLuint shader = glCreateShader(stage);
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    std::string log = InfoLog(shader, false);
    glDeleteShader(shader);
    return MakeError(ErrorCode::kInternal, std::string(stage == GL_VERTEX_SHADER     ? "vertex"
                                                       : stage == GL_FRAGMENT_SHADER ? "fragment"
                                                                                     : "compute") +
                                               " shader does not compile: " + log);
  }
  return shader;
}

}  // namespace

Result<GLuint> LinkProgram(const std::string& vertex_source, const std::string& fragment_source) {
  auto vertex = Compile(GL_VERTEX_SHADER, vertex_source);
  if (!vertex.ok()) return vertex.error();
  auto fragment = Compile(GL_FRAGMENT_SHADER, fragment_source);
  if (!fragment.ok()) {
    glDeleteShader(*vertex);
    return fragment.error();
  }
  GLuint program = glCreateProgram();
  glAttachShader(program, *vertex);
  glAttachShader(program, *fragment);
  glLinkProgram(program);
  glDeleteShader(*vertex);
  glDeleteShader(*fragment);
  GLint ok = GL_FALSE;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    std::string log = InfoLog(program, true);
    glDeleteProgram(program);
    return MakeError(ErrorCode::kInternal, "shader program does not link: " + log);
  }
  return program;
}

Result<GLuint> LinkComputeProgram(const std::string& source) {
  auto shader = Compile(GL_COMPUTE_SHADER, source);
  if (!shader.ok()) return shader.error();
  GLuint program = glCreateProgram();
  glAttachShader(program, *shader);
  glLinkProgram(program);
  glDeleteShader(*shader);
  GLint ok = GL_FALSE;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    std::string log = InfoLog(program, true);
    glDeleteProgram(program);
    return MakeError(ErrorCode::kInternal, "compute program does not link: " + log);
  }
  return program;
}

Result<void> CheckGl(const char* what) {
  const GLenum error = glGetError();
  if (error == GL_NO_ERROR) return {};
  while (glGetError() != GL_NO_ERROR) {
  }
  return MakeError(
      ErrorCode::kInternal, std::string(what) + ": GL error 0x" + [&] {
        char hex[16];
        std::snprintf(hex, sizeof(hex), "%04x", error);
        return std::string(hex);
      }());
}

}  // namespace far::internal
