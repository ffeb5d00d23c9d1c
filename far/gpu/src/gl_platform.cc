#include "far/gpu/gl_platform.h"

#include <array>

namespace far {
namespace {

constexpr std::array<GlPlatform, 3> kPlatforms = {GlPlatform::kAuto, GlPlatform::kDevice,
                                                  GlPlatform::kSurfaceless};

}  // namespace

std::string_view ToString(GlPlatform platform) {
  switch (platform) {
    case GlPlatform::kAuto:
      return "auto";
    case GlPlatform::kDevice:
      return "device";
    case GlPlatform::kSurfaceless:
      return "surfaceless";
  }
  return "unknown";
}

std::optional<GlPlatform> ParseGlPlatform(std::string_view name) {
  for (GlPlatform platform : kPlatforms) {
    if (ToString(platform) == name) return platform;
  }
  return std::nullopt;
}

std::string GlPlatformNames() {
  std::string names;
  for (GlPlatform platform : kPlatforms) {
    if (!names.empty()) names += ", ";
    names += ToString(platform);
  }
  return names;
}

}  // namespace far
