#include "gl_timer.h"

namespace far::internal {

GLuint64 ElapsedNsOrZero(GLuint query, std::chrono::steady_clock::time_point began) {
  GLuint64 ns = 0;
  glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
  const auto wall = std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::steady_clock::now() - began);
  return ns <= static_cast<GLuint64>(wall.count()) ? ns : 0;
}

}  // namespace far::internal
