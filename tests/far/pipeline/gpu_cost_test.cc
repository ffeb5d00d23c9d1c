// The GPU cost `auto` predicts GPU steps from (far::MeasureGpuCost): measured once per process
// and renderer, and replaceable by a cost kept from an earlier run (far::UseGpuCost, which
// far-daemon's cost cache calls at start-up instead of measuring).
#include <gtest/gtest.h>

#include "far/gpu/gl_context.h"
#include "far/pipeline/pipeline.h"

namespace far {
namespace {

TEST(GpuCostTest, ACostGivenToTheProcessIsTheOneAutoIsGivenAfterwards) {
  auto context = GlContext::Create();
  ASSERT_TRUE(context.ok()) << ToString(context.error());
  const std::optional<GpuCost> measured = MeasureGpuCost();
  ASSERT_TRUE(measured);
  EXPECT_GT(measured->Predict(100'000), 0);
  EXPECT_TRUE(measured->compute_fixed_ms) << "the gpu method is measured beside FAR";
  // Measured once: the second call gives the same cost without measuring again.
  EXPECT_EQ(MeasureGpuCost(), measured);

  GpuCost kept{0.25, 1e-6};
  kept.compute_fixed_ms = 0.5;
  kept.compute_ms_per_triangle = 2e-6;
  ASSERT_TRUE(UseGpuCost(kept));
  EXPECT_EQ(MeasureGpuCost(), kept);
  // The process's other tests get the measured cost back.
  ASSERT_TRUE(UseGpuCost(*measured));
  EXPECT_EQ(MeasureGpuCost(), measured);
}

}  // namespace
}  // namespace far
