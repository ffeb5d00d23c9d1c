#pragma once

// The benchmarks' --gl-platform flag (ours, not Google Benchmark's, which rejects flags it does
// not know): auto, device or surfaceless, as far::ParseGlPlatform reads them.

#include "far/gpu/gl_platform.h"

namespace far_study {

/// Takes --gl-platform=X and --gl-platform X out of argv (argc shrinks) into *platform. Returns
/// false, having said why on stderr as `program`, for an unknown platform.
bool TakeGlPlatformFlag(int* argc, char** argv, far::GlPlatform* platform, const char* program);

}  // namespace far_study
