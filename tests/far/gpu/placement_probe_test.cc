// The probe ComputeCollider checks its placement kernel on (no GL): it must tell WorldVertex's
// doubles from those of a device that fused a product into an fma or summed in another order,
// and cover the flush. llvmpipe cannot show this itself: it computes GLSL's fma on doubles
// unfused, so a kernel mutated to use fma still passes there.

#include "placement_probe.h"

#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "far/model/world_vertex.h"

namespace far::internal {
namespace {

// How many coordinates of the probe's placed vertices differ from WorldVertex's when each
// coordinate is computed by `place` (row i of X, the vertex p; before the flush).
template <typename Place>
int DifferingCoordinates(const PlacementProbe& probe, Place place) {
  int differing = 0;
  for (size_t v = 0; v < probe.p_MV.size(); ++v) {
    const Eigen::Matrix<double, 3, 4>& X = probe.X_WM[v / PlacementProbe::kVertices];
    const Eigen::Vector3d exact = WorldVertex(X, probe.p_MV[v]);
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d placed =
          FlushTinyCoordinates(Eigen::Vector3d::Constant(place(X.row(i), probe.p_MV[v])));
      differing += placed[0] != exact[i] ? 1 : 0;
    }
  }
  return differing;
}

TEST(PlacementProbeTest, ShowsADeviceThatFusesOrReorders) {
  const PlacementProbe probe = MakePlacementProbe();
  ASSERT_EQ(probe.p_MV.size(), PlacementProbe::kPoses * PlacementProbe::kVertices);
  using Row = Eigen::Matrix<double, 1, 4>;
  // WorldVertex's own order, as the kernel writes it: no difference (a WorldVertex changed
  // alone, away from the kernel's order, fails here).
  EXPECT_EQ(DifferingCoordinates(probe,
                                 [](const Row& r, const Eigen::Vector3d& p) {
                                   double sum = r[0] * p.x();
                                   sum = sum + r[1] * p.y();
                                   sum = sum + r[2] * p.z();
                                   return sum + r[3];
                                 }),
            0);
  // The products fused into fmas, as a device that ignored `precise` might.
  const int fused = DifferingCoordinates(probe, [](const Row& r, const Eigen::Vector3d& p) {
    return std::fma(r[2], p.z(), std::fma(r[1], p.y(), r[0] * p.x())) + r[3];
  });
  // The translation added first.
  const int reordered = DifferingCoordinates(probe, [](const Row& r, const Eigen::Vector3d& p) {
    double sum = r[3] + r[0] * p.x();
    sum = sum + r[1] * p.y();
    return sum + r[2] * p.z();
  });
  std::printf(
      "of the probe's %zu coordinates, %d differ under fmas, %d with the translation first\n",
      3 * probe.p_MV.size(), fused, reordered);
  EXPECT_GT(fused, 100);
  EXPECT_GT(reordered, 100);
  // Some coordinates are flushed to 0, and some just above the flush are kept.
  int flushed = 0, tiny_kept = 0;
  for (size_t v = 0; v < probe.p_MV.size(); ++v) {
    const Eigen::Matrix<double, 3, 4>& X = probe.X_WM[v / PlacementProbe::kVertices];
    const Eigen::Vector3d placed = WorldVertex(X, probe.p_MV[v]);
    for (int i = 0; i < 3; ++i) {
      double sum = X(i, 0) * probe.p_MV[v].x();
      sum = sum + X(i, 1) * probe.p_MV[v].y();
      sum = sum + X(i, 2) * probe.p_MV[v].z();
      sum = sum + X(i, 3);
      flushed += sum != 0 && placed[i] == 0 ? 1 : 0;
      tiny_kept += placed[i] != 0 && std::abs(placed[i]) < 0x1p-250 ? 1 : 0;
    }
  }
  EXPECT_GT(flushed, 10);
  EXPECT_GT(tiny_kept, 10);
}

}  // namespace
}  // namespace far::internal
