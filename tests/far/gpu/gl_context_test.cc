#include "far/gpu/gl_context.h"

#include <gtest/gtest.h>

namespace far {
namespace {

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

}  // namespace
}  // namespace far
