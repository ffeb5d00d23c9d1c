#include "far/gpu/gl_context.h"

#include <gtest/gtest.h>

namespace far {
namespace {

// NVIDIA's EGL (driver 580, through glvnd) names EGL_EXT_device_base and not the two extensions
// it stands for; Mesa names all three. Both offer the device platform.
TEST(GlContextTest, DevicePlatformIsOfferedUnderEitherExtensionName) {
  EXPECT_TRUE(internal::OffersEglDevicePlatform(
      "EGL_EXT_platform_base EGL_EXT_device_base EGL_KHR_client_get_all_proc_addresses "
      "EGL_EXT_client_extensions EGL_KHR_debug EGL_EXT_platform_device "
      "EGL_MESA_platform_surfaceless EGL_EXT_explicit_device"));
  EXPECT_TRUE(internal::OffersEglDevicePlatform(
      "EGL_EXT_device_enumeration EGL_EXT_device_query EGL_EXT_platform_device"));
  EXPECT_FALSE(internal::OffersEglDevicePlatform("EGL_EXT_device_base EGL_EXT_platform_base"));
  EXPECT_FALSE(internal::OffersEglDevicePlatform("EGL_EXT_platform_device"));
  EXPECT_FALSE(internal::OffersEglDevicePlatform("EGL_EXT_platform_device_base"));
  EXPECT_FALSE(internal::OffersEglDevicePlatform(nullptr));
}

TEST(GlContextTest, CreatesCoreContextAndReportsRenderer) {
  auto context = GlContext::Create();
  ASSERT_TRUE(context.ok()) << ToString(context.error());
  EXPECT_FALSE((*context)->renderer().empty());
  EXPECT_EQ((*context)->version().rfind("4.5", 0), 0u) << (*context)->version();
  EXPECT_FALSE((*context)->platform_description().empty());
  std::printf("GL_RENDERER: %s | GL_VERSION: %s | via %s\n", (*context)->renderer().c_str(),
              (*context)->version().c_str(), (*context)->platform_description().c_str());
}

TEST(GlContextTest, SurfacelessPlatformWorksOnItsOwn) {
  auto context = GlContext::Create(GlPlatform::kSurfaceless);
  ASSERT_TRUE(context.ok()) << ToString(context.error());
  EXPECT_EQ((*context)->platform_description(), "surfaceless");
}

// GlPlatform::kDevice means a GPU. Without one it fails and says what it tried (on Mesa, the
// software EGL device is listed as not a GPU); it never hands out llvmpipe. With one, the
// failure cannot be checked: the test checks the renderer is not a software one, then skips.
TEST(GlContextTest, DevicePlatformGivesAGpuOrSaysNoneWasFound) {
  auto context = GlContext::Create(GlPlatform::kDevice);
  if (context.ok()) {
    const std::string& renderer = (*context)->renderer();
    for (const char* software : {"llvmpipe", "softpipe", "swrast"}) {
      EXPECT_EQ(renderer.find(software), std::string::npos) << renderer;
    }
    EXPECT_NE((*context)->platform_description().find("(hardware)"), std::string::npos)
        << (*context)->platform_description();
    GTEST_SKIP() << "a hardware EGL device exists (" << renderer
                 << "): the no-GPU error cannot be checked on this machine";
  }
  const Error& error = context.error();
  EXPECT_EQ(error.code, ErrorCode::kUnavailable);
  EXPECT_NE(error.message.find("no GPU found through the EGL device platform"), std::string::npos)
      << error.message;
  EXPECT_NE(error.message.find("tried:"), std::string::npos) << error.message;
  if (error.message.find("EGL_MESA_device_software") != std::string::npos) {
    EXPECT_NE(error.message.find("not a GPU"), std::string::npos) << error.message;
  }
  EXPECT_EQ(error.message.find("surfaceless"), std::string::npos)
      << "the device platform must not try the surfaceless platform: " << error.message;
  // The other platforms still give a context on the same machine.
  EXPECT_TRUE(GlContext::Create(GlPlatform::kAuto).ok());
}

}  // namespace
}  // namespace far
