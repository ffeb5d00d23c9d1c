#include "far/pairs/internal/float_bounds.h"

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

namespace far::internal {
namespace {

constexpr float kInfF = std::numeric_limits<float>::infinity();

// `steps` floats from f toward `to`.
float Step(float f, float to, int steps) {
  for (int i = 0; i < steps; ++i) f = std::nextafter(f, to);
  return f;
}

// The bounds hold x, and are at most three float steps away from it.
void ExpectTightOutward(double x) {
  const float below = FloatBelow(x), above = FloatAbove(x);
  EXPECT_LE(static_cast<double>(below), x) << x;
  EXPECT_GE(static_cast<double>(above), x) << x;
  EXPECT_GE(below, Step(static_cast<float>(x), -kInfF, 3)) << x;
  EXPECT_LE(above, Step(static_cast<float>(x), kInfF, 3)) << x;
}

TEST(FloatBoundsTest, HoldEveryValueAcrossMagnitudes) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-160, 127);
  for (int i = 0; i < 200000; ++i) ExpectTightOutward(std::ldexp(mantissa(rng), exponent(rng)));
  // Doubles that are floats already, and their double neighbours, where a plain cast to float
  // rounds to the wrong side half the time.
  std::uniform_real_distribution<float> any(-1e6f, 1e6f);
  for (int i = 0; i < 100000; ++i) {
    const double f = any(rng);
    ExpectTightOutward(f);
    ExpectTightOutward(std::nextafter(f, 0.0));
    ExpectTightOutward(std::nextafter(f, 2 * f + 1));
  }
}

TEST(FloatBoundsTest, ZeroSubnormalsAndTheEndsOfFloatsRange) {
  for (double x : {0.0, -0.0, 0x1p-149, -0x1p-149, 0x1p-160, -0x1p-160, 0x1p-126, 1e-300,
                   static_cast<double>(std::numeric_limits<float>::max())}) {
    ExpectTightOutward(x);
    ExpectTightOutward(-x);
  }
  // Beyond float's range: the outward side is infinite, the inward one the largest float.
  EXPECT_EQ(FloatBelow(1e300), std::numeric_limits<float>::max());
  EXPECT_EQ(FloatAbove(1e300), kInfF);
  EXPECT_EQ(FloatBelow(-1e300), -kInfF);
  EXPECT_EQ(FloatAbove(-1e300), -std::numeric_limits<float>::max());
  EXPECT_EQ(FloatBelow(std::numeric_limits<double>::infinity()), std::numeric_limits<float>::max());
  EXPECT_EQ(FloatAbove(std::numeric_limits<double>::infinity()), kInfF);
  EXPECT_EQ(FloatBelow(-std::numeric_limits<double>::infinity()), -kInfF);
  EXPECT_TRUE(std::isnan(FloatBelow(std::nan(""))));
  EXPECT_TRUE(std::isnan(FloatAbove(std::nan(""))));
}

}  // namespace
}  // namespace far::internal
