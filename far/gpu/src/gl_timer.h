#pragma once

#include <chrono>

#include <epoxy/gl.h>

namespace far::internal {

/// A GL_TIME_ELAPSED query begun at `began` and ended since: its result in nanoseconds, waited
/// for. The GPU cannot have spent longer on the commands than the wall time from the query's
/// begin to its result, so a longer result is no measurement and reads as 0: llvmpipe (Mesa
/// 22.3) returned its clock itself, hours, for some views of far/occlusion-query once the
/// gpu method had run on the same context (far-study's pipelines share one: --scenes
/// bunnies-fine --methods far,gpu), which the study's medians then reported as GPU milliseconds.
/// @pre a GL context is current, the query ended.
GLuint64 ElapsedNsOrZero(GLuint query, std::chrono::steady_clock::time_point began);

}  // namespace far::internal
