#include "gl_platform_flag.h"

#include <cstdio>
#include <cstring>
#include <optional>
#include <string>

namespace far_study {

bool TakeGlPlatformFlag(int* argc, char** argv, far::GlPlatform* platform, const char* program) {
  int kept = 1;
  for (int i = 1; i < *argc; ++i) {
    std::string value;
    if (std::strncmp(argv[i], "--gl-platform=", 14) == 0) {
      value = argv[i] + 14;
    } else if (std::strcmp(argv[i], "--gl-platform") == 0 && i + 1 < *argc) {
      value = argv[++i];
    } else {
      argv[kept++] = argv[i];
      continue;
    }
    const std::optional<far::GlPlatform> parsed = far::ParseGlPlatform(value);
    if (!parsed) {
      std::fprintf(stderr, "%s: --gl-platform: unknown '%s' (%s)\n", program, value.c_str(),
                   far::GlPlatformNames().c_str());
      return false;
    }
    *platform = *parsed;
  }
  *argc = kept;
  argv[kept] = nullptr;
  return true;
}

}  // namespace far_study
