// Snapshots: RenderSnapshot draws marked triangles in their colours on llvmpipe (or a GPU).
// far-snapshot, the program, has its tests in tests/tools/far-snapshot.

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "far/gpu/gl_context.h"
#include "far/gpu/snapshot_renderer.h"
#include "far/scenes/scenes.h"

namespace far {
namespace {

// Pixels that are plainly the contact colour (lit or in shade), not grey, yellow, orange or the
// background, nor a faded contact seen through something else.
bool IsContactRed(const uint8_t* p) { return p[0] >= 60 && p[0] > 3 * p[1] && p[0] > 3 * p[2]; }
bool IsPcsYellow(const uint8_t* p) { return p[0] >= 60 && p[1] > p[0] * 6 / 10 && p[2] * 3 < p[1]; }

size_t Count(const std::vector<uint8_t>& rgb, bool (*is)(const uint8_t*)) {
  size_t n = 0;
  for (size_t i = 0; i + 2 < rgb.size(); i += 3) n += is(&rgb[i]) ? 1 : 0;
  return n;
}

class SnapshotRendererTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto context = GlContext::Create();
    ASSERT_TRUE(context.ok()) << ToString(context.error());
    context_ = std::move(*context);
  }
  std::unique_ptr<GlContext> context_;
  Mesh sphere_ = scenes::SphereMesh(Eigen::Vector3d::Zero(), 0.5, 8, 16);
};

TEST_F(SnapshotRendererTest, DrawsEachMarkInItsColourOnTheBackground) {
  std::vector<SnapshotObject> objects(2);
  objects[0].mesh = objects[1].mesh = &sphere_;
  objects[1].X_WO.translation = Eigen::Vector3d(1.5, 0, 0);
  SnapshotOptions options;
  options.width = 160;
  options.height = 120;
  auto plain = RenderSnapshot(objects, options);
  ASSERT_TRUE(plain.ok()) << ToString(plain.error());
  EXPECT_EQ(plain->width, 160);
  EXPECT_EQ(plain->height, 120);
  ASSERT_EQ(plain->rgb.size(), 160u * 120 * 3);
  EXPECT_EQ(Count(plain->rgb, IsContactRed), 0u);
  EXPECT_EQ(Count(plain->rgb, IsPcsYellow), 0u);
  // The corner is background; the centre of the picture is an object (grey).
  const Eigen::Vector3f background = SnapshotBackground() * 255.0f;
  EXPECT_NEAR(plain->rgb[0], background.x(), 1.5);
  EXPECT_NEAR(plain->rgb[2], background.z(), 1.5);

  objects[0].marks.assign(sphere_.triangles.size(), TriangleMark::kPcs);
  objects[1].marks.assign(sphere_.triangles.size(), TriangleMark::kContact);
  auto marked = RenderSnapshot(objects, options);
  ASSERT_TRUE(marked.ok()) << ToString(marked.error());
  EXPECT_GT(Count(marked->rgb, IsContactRed), 200u);
  EXPECT_GT(Count(marked->rgb, IsPcsYellow), 200u);
}

TEST_F(SnapshotRendererTest, RejectsBadInput) {
  std::vector<SnapshotObject> objects(1);
  objects[0].mesh = &sphere_;
  SnapshotOptions options;
  options.width = 8;
  EXPECT_EQ(RenderSnapshot(objects, options).error().code, ErrorCode::kInvalidArgument);
  objects[0].marks.assign(3, TriangleMark::kPcs);
  auto mismatch = RenderSnapshot(objects);
  ASSERT_FALSE(mismatch.ok());
  EXPECT_NE(mismatch.error().message.find("3 marks for 224 triangles"), std::string::npos)
      << mismatch.error().message;
  objects[0].mesh = nullptr;
  EXPECT_EQ(RenderSnapshot(objects).error().code, ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace far
