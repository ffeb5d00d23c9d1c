// Every answer carries its certificate (far::Certificate): whether the method guarantees every
// contact, in words, and for the GPU methods the numbers each culling level used. The numbers
// must be the ones that make the answer hold: r covers D/2, the pixel and depth steps and the
// float32 rounding, and the level's bounds hold every primitive that took part.
#include <cmath>
#include <set>

#include "test_scenes.h"
#include <gtest/gtest.h>

#include "far/pipeline/pipeline.h"

namespace far {
namespace {

class CertificateTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto pipeline = Pipeline::Create();
    ASSERT_TRUE(pipeline.ok()) << ToString(pipeline.error());
    pipeline_ = std::move(*pipeline).release();
    objects_ = new std::vector<SceneObject>(testing::RandomSoup(7, 6, 12, 2.0, 0.6));
    for (const auto& object : *objects_)
      ASSERT_TRUE(pipeline_->AddObject(object.id, object.mesh, object.motion, object.X_WO).ok());
  }
  static void TearDownTestSuite() {
    delete pipeline_;
    delete objects_;
  }

  static StepResult Run(Method method, std::optional<double> distance = std::nullopt) {
    StepRequest request;
    request.method = method;
    request.resolution = 64;
    request.distance = distance;
    request.output = distance ? Output::kDistancePairs : Output::kContacts;
    auto result = pipeline_->Step(request);
    EXPECT_TRUE(result.ok()) << ToString(result.error());
    return result.ok() ? std::move(*result) : StepResult{};
  }

  // The world box of every triangle of the objects in the PCS.
  static Eigen::AlignedBox3d PcsBounds(const StepResult& result) {
    const std::set<uint32_t> pcs(result.pcs_objects.begin(), result.pcs_objects.end());
    Eigen::AlignedBox3d box;
    for (const auto& object : *objects_) {
      if (!pcs.count(object.id)) continue;
      for (const auto& p : object.mesh.p_MV) box.extend(object.X_WO.ToIsometry() * p);
    }
    return box;
  }

  static Pipeline* pipeline_;
  static std::vector<SceneObject>* objects_;
};
Pipeline* CertificateTest::pipeline_ = nullptr;
std::vector<SceneObject>* CertificateTest::objects_ = nullptr;

TEST_F(CertificateTest, CpuMethodsSayWhyAndHaveNoLevels) {
  for (Method method : {Method::kExact, Method::kBvh, Method::kAabb}) {
    const StepResult result = Run(method);
    EXPECT_TRUE(result.stats.certificate.guaranteed) << ToString(method);
    EXPECT_EQ(result.stats.certificate.basis.rfind("guaranteed: ", 0), 0u)
        << result.stats.certificate.basis;
    EXPECT_TRUE(result.stats.certificate.levels.empty()) << ToString(method);
  }
  const StepResult fcl = Run(Method::kFcl);
  EXPECT_FALSE(fcl.stats.certificate.guaranteed);
  EXPECT_NE(fcl.stats.certificate.basis.find("not guaranteed"), std::string::npos);
}

TEST_F(CertificateTest, FarLevelsShowWhatTheRadiusCovers) {
  for (std::optional<double> distance : {std::optional<double>{}, std::optional<double>{0.05}}) {
    for (Method method : {Method::kFar, Method::kFarExactOffset}) {
      const StepResult result = Run(method, distance);
      const Certificate& certificate = result.stats.certificate;
      EXPECT_TRUE(certificate.guaranteed);
      EXPECT_NE(certificate.basis.find("radius r >= D/2"), std::string::npos) << certificate.basis;
      ASSERT_EQ(certificate.levels.size(), 2u) << ToString(method);
      EXPECT_EQ(certificate.levels[0].level, "object");
      EXPECT_EQ(certificate.levels[1].level, "sub-object");
      for (const LevelCertificate& level : certificate.levels) {
        SCOPED_TRACE(std::string(ToString(method)) + " " + level.level);
        EXPECT_GE(level.views, 1);
        EXPECT_LE(level.views, 3);
        EXPECT_EQ(level.resolution, 64);
        EXPECT_GT(level.pixel_size, 0);
        EXPECT_GT(level.depth_step, 0);
        EXPECT_GT(level.rounding, 0);
        EXPECT_LT(level.depth_step, level.pixel_size);  // 24-bit depth, 64 pixels
        const double covered = 0.5 * distance.value_or(0) +
                               std::sqrt(3.0) * std::max(level.pixel_size, level.depth_step) +
                               level.rounding;
        EXPECT_GE(level.offset_radius, covered);
        // The pixel is the level's extent over the resolution: the bounds hold every primitive
        // drawn, so the pixel spans at least their extent / 64.
        const Eigen::Vector3d lo(level.world_min.data()), hi(level.world_max.data());
        EXPECT_GE(level.pixel_size * 64, (hi - lo).maxCoeff());
      }
      // The object level drew every object of the PCS: its bounds hold them.
      const LevelCertificate& object_level = certificate.levels[0];
      const Eigen::AlignedBox3d pcs = PcsBounds(result);
      for (int i = 0; i < 3; ++i) {
        EXPECT_LE(object_level.world_min[i], pcs.min()[i]);
        EXPECT_GE(object_level.world_max[i], pcs.max()[i]);
      }
      EXPECT_EQ(result.stats.object_radius, object_level.offset_radius);
      EXPECT_EQ(result.stats.primitive_radius, certificate.levels[1].offset_radius);
    }
  }
}

TEST_F(CertificateTest, CullideSaysItDrawsNoOffset) {
  const StepResult result = Run(Method::kCullide);
  EXPECT_FALSE(result.stats.certificate.guaranteed);
  EXPECT_NE(result.stats.certificate.basis.find("offset radius 0"), std::string::npos);
  ASSERT_FALSE(result.stats.certificate.levels.empty());
  for (const LevelCertificate& level : result.stats.certificate.levels)
    EXPECT_EQ(level.offset_radius, 0);
}

TEST_F(CertificateTest, AutoCarriesTheCertificateOfWhatItChose) {
  const StepResult result = Run(Method::kAuto);
  EXPECT_TRUE(result.stats.certificate.guaranteed) << result.stats.method;
  EXPECT_FALSE(result.stats.certificate.basis.empty());
}

}  // namespace
}  // namespace far
