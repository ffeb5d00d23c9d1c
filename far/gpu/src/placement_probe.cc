#include "placement_probe.h"

#include <cmath>
#include <random>

#include <Eigen/Geometry>

namespace far::internal {

PlacementProbe MakePlacementProbe() {
  constexpr int kScales[PlacementProbe::kPoses] = {0, 39, -20, 12, -255, -258, -100, 30};
  std::mt19937_64 random(20261130);
  std::uniform_real_distribution<double> unit(-1, 1);
  PlacementProbe probe;
  for (int scale : kScales) {
    const auto number = [&] { return std::ldexp(unit(random), scale); };
    Eigen::Quaterniond q(unit(random), unit(random), unit(random), unit(random));
    q.normalize();
    Eigen::Matrix<double, 3, 4> X;
    X.leftCols<3>() = q.toRotationMatrix();
    X.col(3) = Eigen::Vector3d(number(), number(), number());
    for (size_t v = 0; v < PlacementProbe::kVertices; ++v)
      probe.p_MV.emplace_back(number(), number(), number());
    if (probe.X_WM.size() % 2 == 1)
      probe.p_MV.back() = -(X.leftCols<3>().transpose() * X.col(3));  // R p + t = 0, rounded
    probe.X_WM.push_back(X);
  }
  return probe;
}

}  // namespace far::internal
