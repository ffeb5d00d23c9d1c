#pragma once

#include <string>

#include <epoxy/gl.h>

#include "far/base/result.h"

namespace far::internal {

/// Compiles and links a vertex + fragment shader program. Returns kInternal with the driver's
/// info log when either stage fails. @pre a GL context is current on this thread.
Result<GLuint> LinkProgram(const std::string& vertex_source, const std::string& fragment_source);

/// Compiles and links a compute shader program. Returns kInternal with the driver's info log
/// when it fails. @pre a GL 4.3+ context is current on this thread.
Result<GLuint> LinkComputeProgram(const std::string& source);

/// Returns kInternal naming `what` and the GL error if glGetError reports one (clears it).
Result<void> CheckGl(const char* what);

}  // namespace far::internal
