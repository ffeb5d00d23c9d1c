#pragma once

// The EGL platform a GL context may come from, and its one parser: the daemon's flag and config
// file, far-snapshot and the studies all name platforms through these.

#include <optional>
#include <string>
#include <string_view>

namespace far {

/// Which EGL platform a context may come from.
enum class GlPlatform {
  kAuto,         ///< EGL device platform (hardware first), then Mesa surfaceless
  kDevice,       ///< EGL_EXT_platform_device, hardware devices (GPUs) only: never software
  kSurfaceless,  ///< EGL_MESA_platform_surfaceless only (llvmpipe on machines with no GPU)
};

/// "auto", "device" or "surfaceless".
std::string_view ToString(GlPlatform platform);
/// The platform named `name` (ToString's inverse), or nullopt.
std::optional<GlPlatform> ParseGlPlatform(std::string_view name);
/// The known names, comma-separated, for help texts and errors: "auto, device, surfaceless".
std::string GlPlatformNames();

}  // namespace far
