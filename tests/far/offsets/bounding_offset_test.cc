// ComputeProjection and DepthResolution: the offset radius satisfies Theorem 1 (with distance
// culling and the float32 error) for the bounds it returns, and the bounds strictly contain
// every fattened primitive, as computed in double and as rounded to float32.

#include "far/offsets/bounding_offset.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "far/offsets/offset_test_support.h"

namespace far {
namespace {

constexpr double kSqrt3 = 1.7320508075688772935;

struct Scene {
  std::vector<test::Triangle> triangles;
  std::vector<Obb> rects;
  Eigen::AlignedBox3d rect_bounds_W;  // from the rectangles' corners
};

Scene MakeScene(std::vector<test::Triangle> triangles) {
  Scene scene;
  scene.triangles = std::move(triangles);
  for (const auto& t : scene.triangles) {
    scene.rects.push_back(TriangleRectangle(t.a, t.b, t.c));
    for (const auto& corner : ObbCorners(scene.rects.back())) scene.rect_bounds_W.extend(corner);
  }
  return scene;
}

// Triangles of every family with size `scale`, spread over a cube of side `spread` at `base`.
std::vector<test::Triangle> RandomTriangles(std::mt19937_64& rng, double scale, double spread,
                                            const Eigen::Vector3d& base, int groups) {
  std::vector<test::Triangle> triangles;
  std::uniform_real_distribution<double> unit(-0.5, 0.5);
  for (int g = 0; g < groups; ++g) {
    const Eigen::Vector3d at = base + spread * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    for (auto& t : test::TriangleFamilies(rng, scale, at)) triangles.push_back(t);
  }
  return triangles;
}

double Resolution(const RasterFormat& raster) {
  return std::min({static_cast<double>(raster.width), static_cast<double>(raster.height),
                   DepthResolution(raster.depth)});
}

// Every point the GPU will be given for this scene: UOBB corners and bounded exact offsets.
std::vector<Eigen::Vector3d> FattenedVertices(const Scene& scene, double r) {
  std::vector<Eigen::Vector3d> points;
  for (size_t i = 0; i < scene.rects.size(); ++i) {
    for (const auto& p : ObbCorners(GrowObb(scene.rects[i], r))) points.push_back(p);
    const auto& t = scene.triangles[i];
    const auto offset = ComputeBoundedExactOffset(t.a, t.b, t.c, r);
    for (const auto& box : offset.edge_boxes) {
      for (const auto& p : ObbCorners(box)) points.push_back(p);
    }
    for (const auto& p : offset.prism) points.push_back(p);
  }
  return points;
}

// Checks the projection's guarantees for the scene; returns the number of failed checks.
int CheckProjection(const Scene& scene, const RasterFormat& raster, double distance,
                    const Projection& projection, const std::string& what) {
  int failures = 0;
  const auto fail = [&](const std::string& message) {
    if (++failures <= 3) ADD_FAILURE() << what << ": " << message;
  };
  const double r = projection.radius;
  const Eigen::AlignedBox3d& bounds = projection.bounds_W;
  if (!(r > 0 && std::isfinite(r))) fail("radius " + std::to_string(r));
  if (!bounds.min().allFinite() || !bounds.max().allFinite()) fail("bounds not finite");
  if (!(bounds.sizes().array() > 0).all()) fail("bounds have an empty side");
  if (!projection.center_W.isApprox(bounds.center(), 1e-15) &&
      (projection.center_W - bounds.center()).norm() > 0) {
    fail("center is not the bounds' center");
  }

  // Theorem 1 with the cells recomputed from the returned bounds, and the float32 term: at
  // least the 18 roundings of 2^-24 (H + r) counted in the derivation.
  const double res = Resolution(raster);
  const double extent = bounds.sizes().maxCoeff();
  const double p = 2 * extent / res;  // max over axes of 2 d_A
  const double theorem = 0.5 * distance + kSqrt3 / 2 * p;
  if (!(r >= theorem)) fail("r " + std::to_string(r) + " < theorem " + std::to_string(theorem));
  const double float_term = kSqrt3 * 18 * 0x1p-24 * (0.5 * extent + r);
  if (!(r >= theorem + float_term)) fail("r lacks the float32 term");

  // What the projection reports it covers (a reply's certificate shows it) is what it covers.
  if (projection.pixel_size != extent / std::min(raster.width, raster.height))
    fail("pixel_size is not the largest pixel side");
  if (projection.depth_step != extent / DepthResolution(raster.depth))
    fail("depth_step is not the largest depth step");
  if (!(projection.rounding >= float_term)) fail("rounding is below the float32 term");
  const double covered = 0.5 * distance +
                         kSqrt3 * std::max(projection.pixel_size, projection.depth_step) +
                         projection.rounding;
  if (!(r >= covered)) fail("r is below what the projection says it covers");

  // Strict containment in double, and of the float32 local coordinates the GPU sees.
  const Eigen::Vector3d lo = bounds.min() - projection.center_W;
  const Eigen::Vector3d hi = bounds.max() - projection.center_W;
  for (const auto& point : FattenedVertices(scene, r)) {
    if (!((point.array() > bounds.min().array()).all() &&
          (point.array() < bounds.max().array()).all())) {
      fail("vertex outside the bounds");
    }
    const Eigen::Vector3d local = (point - projection.center_W).cast<float>().cast<double>();
    if (!((local.array() > lo.array()).all() && (local.array() < hi.array()).all())) {
      fail("float32 local vertex outside the bounds");
    }
  }
  return failures;
}

TEST(DepthResolutionTest, IsOneOverTheLargestDepthStep) {
  EXPECT_EQ(DepthResolution(DepthFormat::kDepth16), 65535.0);
  EXPECT_EQ(DepthResolution(DepthFormat::kDepth24), 16777215.0);
  EXPECT_EQ(DepthResolution(DepthFormat::kDepth32F), 16777216.0);
  // float32 depth: the step just below 1 is 2^-24.
  EXPECT_EQ(1.0 - static_cast<double>(std::nextafter(1.0f, 0.0f)), 1.0 / 16777216.0);
}

TEST(ComputeProjectionTest, RadiusAndBoundsHoldForRandomScenes) {
  std::mt19937_64 rng(31337);
  const int sizes[] = {8, 32, 100, 1024, 2048};
  const DepthFormat formats[] = {DepthFormat::kDepth16, DepthFormat::kDepth24,
                                 DepthFormat::kDepth32F};
  int failures = 0, cases = 0;
  for (double scale : {1e-6, 1e-3, 1.0, 1e3, 1e6}) {
    for (double translation : {0.0, 1.0, 1e3, 1e6}) {
      std::uniform_real_distribution<double> coordinate(-translation, translation);
      const Eigen::Vector3d base(coordinate(rng), coordinate(rng), coordinate(rng));
      for (double spread : {0.0, 3.0, 100.0}) {
        const Scene scene = MakeScene(RandomTriangles(rng, scale, spread * scale, base, 3));
        for (DepthFormat format : formats) {
          for (int width : sizes) {
            const int height = sizes[(cases + 2) % 5];
            for (double distance : {0.0, 0.01 * scale, 5 * scale}) {
              const RasterFormat raster{width, height, format};
              const Projection projection =
                  ComputeProjection(scene.rect_bounds_W, raster, distance);
              const std::string what =
                  "scale " + std::to_string(scale) + " translation " + std::to_string(translation) +
                  " spread " + std::to_string(spread) + " raster " + std::to_string(width) + "x" +
                  std::to_string(height) + " D " + std::to_string(distance);
              failures += CheckProjection(scene, raster, distance, projection, what);
              ++cases;
            }
          }
        }
      }
    }
  }
  EXPECT_EQ(failures, 0) << "in " << cases << " cases";
}

// A frame whose row `axis` is (1, 1, 1)/sqrt 3 puts UOBB corners exactly sqrt(3) r beyond the
// rectangle along that world axis: the worst case the bounds' growth is derived for.
TEST(ComputeProjectionTest, BoundsHoldWhereTheSqrt3ReachIsAttained) {
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> angle(0, 2 * std::numbers::pi);
  Eigen::Matrix3d q;
  q.row(0) = Eigen::Vector3d(1, 1, 1) / std::sqrt(3.0);
  q.row(1) = Eigen::Vector3d(1, -1, 0) / std::sqrt(2.0);
  q.row(2) = Eigen::Vector3d(1, 1, -2) / std::sqrt(6.0);
  int failures = 0;
  for (double scale : {1e-6, 1.0, 1e6}) {
    for (double translation : {0.0, 1e3, 1e6}) {
      for (int trial = 0; trial < 40; ++trial) {
        const int axis = trial % 3;
        // Rotating about world axis `axis` keeps that row; a cyclic shift moves it there.
        Eigen::Matrix3d shift = Eigen::Matrix3d::Zero();
        for (int i = 0; i < 3; ++i) shift((i + axis) % 3, i) = 1;
        const Eigen::Matrix3d axes =
            Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::Unit(axis)).toRotationMatrix() * shift *
            q;
        const Eigen::Vector3d base = translation * test::RandomDirection(rng);
        const Eigen::Vector3d u = axes.col(0), v = axes.col(1);
        const Scene scene =
            MakeScene({{base, base + scale * u, base + scale * (0.5 * u + 0.4 * v), "diagonal"}});
        for (int res : {8, 1024}) {
          const RasterFormat raster{res, res, DepthFormat::kDepth32F};
          const Projection projection = ComputeProjection(scene.rect_bounds_W, raster, 0);
          failures += CheckProjection(scene, raster, 0, projection, "diagonal");
        }
      }
    }
  }
  EXPECT_EQ(failures, 0);
}

TEST(ComputeProjectionTest, RadiusIsNotMuchLargerThanTheFixedPoint) {
  std::mt19937_64 rng(7);
  for (double scale : {1e-6, 1.0, 1e6}) {
    for (int res : {8, 64, 1024, 2048}) {
      const Scene scene =
          MakeScene(RandomTriangles(rng, scale, 50 * scale, Eigen::Vector3d::Zero(), 4));
      const double distance = 0.1 * scale;
      const RasterFormat raster{res, res, DepthFormat::kDepth24};
      const double r = ComputeProjection(scene.rect_bounds_W, raster, distance).radius;
      const double e = scene.rect_bounds_W.sizes().maxCoeff();
      const double fixed_point = (0.5 * distance + kSqrt3 * e / res) / (1 - 6.0 / res);
      EXPECT_GE(r, fixed_point);
      EXPECT_LE(r, 1.05 * fixed_point) << "scale " << scale << " res " << res;
    }
  }
}

TEST(ComputeProjectionTest, TranslatedSceneGetsTheSameRadius) {
  std::mt19937_64 rng(8);
  for (double scale : {1e-3, 1.0}) {
    const auto triangles = RandomTriangles(rng, scale, 20 * scale, Eigen::Vector3d::Zero(), 3);
    const Eigen::Vector3d shift(1e5, -1e5, 3e4);
    std::vector<test::Triangle> moved = triangles;
    for (auto& t : moved) t.a += shift, t.b += shift, t.c += shift;
    const RasterFormat raster{1024, 1024, DepthFormat::kDepth24};
    const double r0 = ComputeProjection(MakeScene(triangles).rect_bounds_W, raster, 0).radius;
    const Projection p1 = ComputeProjection(MakeScene(moved).rect_bounds_W, raster, 0);
    EXPECT_NEAR(p1.radius, r0, (scale < 1 ? 1e-4 : 1e-6) * r0) << "scale " << scale;
    EXPECT_EQ(CheckProjection(MakeScene(moved), raster, 0, p1, "moved"), 0);
  }
}

TEST(ComputeProjectionTest, DegenerateBoundsGiveFinitePositiveRadius) {
  const RasterFormat raster{256, 128, DepthFormat::kDepth16};
  for (const Eigen::Vector3d& point :
       {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1e6, -1e6, 3), Eigen::Vector3d(1e-300, 0, 0)}) {
    for (double distance : {0.0, 1e-3}) {
      const Projection projection =
          ComputeProjection(Eigen::AlignedBox3d(point, point), raster, distance);
      EXPECT_TRUE(projection.radius > 0 && std::isfinite(projection.radius));
      EXPECT_GE(projection.radius, 0.5 * distance);
      EXPECT_TRUE((projection.bounds_W.min().array() < point.array()).all());
      EXPECT_TRUE((projection.bounds_W.max().array() > point.array()).all());
      // A degenerate triangle at that point stays inside, fattened, in double and float32.
      const Scene scene = MakeScene({{point, point, point, "coincident"}});
      EXPECT_EQ(CheckProjection(scene, raster, distance, projection, "point"), 0);
    }
  }
  // A flat scene: zero extent along z.
  const Eigen::AlignedBox3d flat(Eigen::Vector3d(-1, -2, 5), Eigen::Vector3d(3, 4, 5));
  const Projection projection = ComputeProjection(flat, raster, 0);
  EXPECT_GT(projection.bounds_W.sizes().z(), 0);
  EXPECT_GE(projection.radius, kSqrt3 * projection.bounds_W.sizes().maxCoeff() / 128);
}

TEST(ComputeProjectionTest, RejectsViolatedPreconditions) {
  const Eigen::AlignedBox3d box(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  const auto message = [](auto&& call) -> std::string {
    try {
      call();
    } catch (const std::invalid_argument& error) {
      return error.what();
    }
    return "no exception";
  };
  EXPECT_NE(message([&] {
              (void)ComputeProjection(box, {4, 1024, DepthFormat::kDepth24}, 0);
            }).find("below 8x8"),
            std::string::npos);
  EXPECT_NE(message([&] { (void)ComputeProjection(Eigen::AlignedBox3d(), {}, 0); }).find("empty"),
            std::string::npos);
  const Eigen::AlignedBox3d nan(Eigen::Vector3d(0, 0, std::nan("")), Eigen::Vector3d::Ones());
  EXPECT_NE(message([&] { (void)ComputeProjection(nan, {}, 0); }).find("not finite"),
            std::string::npos);
  EXPECT_NE(message([&] { (void)ComputeProjection(box, {}, -1); }).find("distance"),
            std::string::npos);
}

}  // namespace
}  // namespace far
