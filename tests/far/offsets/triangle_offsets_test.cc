// TriangleRectangle and ComputeBoundedExactOffset: frames, tightness, degenerate triangles,
// and the randomized guarantee that every point of the triangle grown by a ball of radius r
// lies inside its UOBB and inside the union of its bounded exact offset's pieces.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "far/offsets/bounding_offset.h"
#include "far/offsets/offset_test_support.h"

namespace far {
namespace {

using test::Triangle;

constexpr double kScales[] = {1e-6, 1e-3, 1.0, 1e3, 1e6};
constexpr double kTranslations[] = {0.0, 1.0, 1e3, 1e6};

// Checks the frame is finite, orthonormal and right-handed.
void ExpectOrthonormal(const Eigen::Matrix3d& axes, const std::string& what) {
  ASSERT_TRUE(axes.allFinite()) << what;
  EXPECT_LE((axes.transpose() * axes - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-14)
      << what;
  EXPECT_NEAR(axes.determinant(), 1.0, 1e-14) << what;
}

TEST(TriangleRectangleTest, IsTightForASimpleTriangle) {
  const Obb rect = TriangleRectangle({0, 0, 0}, {4, 0, 0}, {1, 2, 0});
  EXPECT_TRUE(rect.axes.isApprox(Eigen::Matrix3d::Identity(), 1e-15));
  EXPECT_TRUE(rect.center.isApprox(Eigen::Vector3d(2, 1, 0), 1e-14));
  EXPECT_NEAR(rect.half_extents.x(), 2, 1e-12);
  EXPECT_NEAR(rect.half_extents.y(), 1, 1e-12);
  EXPECT_NEAR(rect.half_extents.z(), 0, 1e-12);
  EXPECT_GT(rect.half_extents.z(), 0);  // the slack that covers rounding
}

TEST(TriangleRectangleTest, NormalFollowsTheWinding) {
  const Obb reversed = TriangleRectangle({0, 0, 0}, {1, 2, 0}, {4, 0, 0});
  EXPECT_TRUE(reversed.axes.col(0).isApprox(Eigen::Vector3d(-1, 0, 0), 1e-15));
  EXPECT_TRUE(reversed.axes.col(2).isApprox(Eigen::Vector3d(0, 0, -1), 1e-15));
  ExpectOrthonormal(reversed.axes, "reversed");
}

TEST(TriangleRectangleTest, FirstAxisFollowsTheLongestEdge) {
  const Eigen::Vector3d a(1, 1, 1), b(1, 4, 1), c(2, 0, 1);  // bc is longest
  const Obb rect = TriangleRectangle(a, b, c);
  EXPECT_NEAR(std::abs(rect.axes.col(0).dot((c - b).normalized())), 1.0, 1e-15);
  EXPECT_NEAR(rect.half_extents.x(), 0.5 * (c - b).norm(), 1e-12);
}

TEST(TriangleRectangleTest, CoincidentVerticesGiveAPointWithIdentityAxes) {
  const Eigen::Vector3d p(3e5, -2, 7);
  const Obb rect = TriangleRectangle(p, p, p);
  EXPECT_EQ(rect.axes, Eigen::Matrix3d::Identity());
  EXPECT_EQ(rect.center, p);
  EXPECT_LE(rect.half_extents.maxCoeff(), 1e-8);
  EXPECT_TRUE(TriangleRectangle({0, 0, 0}, {0, 0, 0}, {0, 0, 0}).half_extents.allFinite());
}

TEST(TriangleRectangleTest, CollinearTriangleGivesASegment) {
  const Obb rect = TriangleRectangle({0, 0, 0}, {0, 0, 8}, {0, 0, 3});
  ExpectOrthonormal(rect.axes, "collinear");
  EXPECT_NEAR(std::abs(rect.axes(2, 0)), 1.0, 1e-15);
  EXPECT_NEAR(rect.half_extents.x(), 4, 1e-12);
  EXPECT_LE(rect.half_extents.y(), 1e-12);
  EXPECT_LE(rect.half_extents.z(), 1e-12);
  // Deterministic: the same input gives the same frame.
  EXPECT_EQ(rect.axes, TriangleRectangle({0, 0, 0}, {0, 0, 8}, {0, 0, 3}).axes);
}

TEST(TriangleRectangleTest, FramesAreOrthonormalForEveryFamily) {
  std::mt19937_64 rng(11);
  for (double scale : kScales) {
    for (double translation : kTranslations) {
      const Eigen::Vector3d base = translation * test::RandomDirection(rng);
      for (const Triangle& t : test::TriangleFamilies(rng, scale, base)) {
        const Obb rect = TriangleRectangle(t.a, t.b, t.c);
        ExpectOrthonormal(rect.axes, t.kind);
        ASSERT_TRUE(rect.center.allFinite() && rect.half_extents.allFinite()) << t.kind;
        // The normal follows the winding wherever the triangle's area is well above rounding.
        using V = Eigen::Matrix<long double, 3, 1>;
        const V cross = (t.b - t.a).cast<long double>().cross((t.c - t.a).cast<long double>());
        const double longest =
            std::max({(t.b - t.a).norm(), (t.c - t.b).norm(), (t.a - t.c).norm()});
        if (cross.norm() > 1e-7L * longest * longest) {
          const Eigen::Vector3d unit_cross = (cross / cross.norm()).cast<double>();
          EXPECT_GT(rect.axes.col(2).dot(unit_cross), 1 - 1e-6) << t.kind;
        }
        const BoundedExactOffset offset = ComputeBoundedExactOffset(t.a, t.b, t.c, scale);
        for (const Obb& box : offset.edge_boxes) {
          ExpectOrthonormal(box.axes, t.kind + " edge box");
          ASSERT_TRUE(box.center.allFinite() && box.half_extents.allFinite()) << t.kind;
        }
        for (const auto& p : offset.prism) ASSERT_TRUE(p.allFinite()) << t.kind;
      }
    }
  }
}

TEST(BoundedExactOffsetTest, PiecesMatchThePaper) {
  const Eigen::Vector3d a(0, 0, 0), b(4, 0, 0), c(1, 2, 0);
  const double r = 0.25;
  const BoundedExactOffset offset = ComputeBoundedExactOffset(a, b, c, r);
  const std::array<Eigen::Vector3d, 3> v = {a, b, c};
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d e = v[(i + 1) % 3] - v[i];
    const Obb& box = offset.edge_boxes[i];
    EXPECT_TRUE(box.center.isApprox(v[i] + 0.5 * e, 1e-15));
    EXPECT_TRUE(box.axes.col(0).isApprox(e.normalized(), 1e-15));
    EXPECT_TRUE(box.axes.col(2).isApprox(Eigen::Vector3d(0, 0, 1), 1e-15));
    EXPECT_NEAR(box.half_extents.x(), 0.5 * e.norm() + r, 1e-12);
    EXPECT_NEAR(box.half_extents.y(), r, 1e-12);
    EXPECT_NEAR(box.half_extents.z(), r, 1e-12);
    EXPECT_GE(box.half_extents.y(), r);
  }
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(offset.prism[i].isApprox(v[i] + Eigen::Vector3d(0, 0, r), 1e-12));
    EXPECT_TRUE(offset.prism[i + 3].isApprox(v[i] - Eigen::Vector3d(0, 0, r), 1e-12));
    EXPECT_GE(offset.prism[i].z(), r);
  }
  // 3 boxes of 8 corners and a prism of 6: the paper's 30 vertices.
  EXPECT_EQ(3 * 8 + offset.prism.size(), 30u);
}

TEST(BoundedExactOffsetTest, PrismIsOutwardForBothWindings) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::Vector3d a = test::RandomInBall(rng, 1), b = test::RandomInBall(rng, 1),
                    c = test::RandomInBall(rng, 1);
    if (trial % 2) std::swap(b, c);
    const auto offset = ComputeBoundedExactOffset(a, b, c, 0.1);
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const auto& p : offset.prism) centroid += p / 6;
    for (size_t f = 0; f < kPrismTriangleCorners.size(); f += 3) {
      const auto& p0 = offset.prism[kPrismTriangleCorners[f]];
      const auto& p1 = offset.prism[kPrismTriangleCorners[f + 1]];
      const auto& p2 = offset.prism[kPrismTriangleCorners[f + 2]];
      const Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0);
      EXPECT_GT(normal.dot((p0 + p1 + p2) / 3 - centroid), 0)
          << "trial " << trial << " face " << f / 3;
    }
  }
}

TEST(BoundedExactOffsetTest, PrismTrianglesAreClosed) {
  // Every directed edge appears exactly once and its reverse exactly once.
  int count[6][6] = {};
  for (size_t f = 0; f < kPrismTriangleCorners.size(); f += 3) {
    for (int k = 0; k < 3; ++k) {
      ++count[kPrismTriangleCorners[f + k]][kPrismTriangleCorners[f + (k + 1) % 3]];
    }
  }
  int edges = 0;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      EXPECT_LE(count[i][j], 1) << i << "->" << j;
      EXPECT_EQ(count[i][j], count[j][i]) << i << "->" << j;
      edges += count[i][j];
    }
  }
  EXPECT_EQ(edges, 24);  // 12 undirected edges of a triangulated prism (V - E + F = 2)
}

TEST(BoundedExactOffsetTest, DegenerateTrianglesKeepThePrismInsideTheEdgeBoxes) {
  std::mt19937_64 rng(17);
  for (double scale : kScales) {
    const Eigen::Vector3d base = 1e3 * test::RandomDirection(rng);
    for (const Triangle& t : test::TriangleFamilies(rng, scale, base)) {
      // Exactly degenerate only (a near-collinear triangle may have a trustworthy normal).
      if (t.kind.rfind("collinear", 0) != 0 && t.kind.find("repeated") == std::string::npos &&
          t.kind != "coincident") {
        continue;
      }
      const double r = 0.01 * scale;
      const auto offset = ComputeBoundedExactOffset(t.a, t.b, t.c, r);
      for (const auto& p : offset.prism) {
        bool inside = false;
        for (const Obb& box : offset.edge_boxes) inside = inside || test::InsideObb(box, p);
        EXPECT_TRUE(inside) << t.kind << " scale " << scale;
      }
    }
  }
}

// The guarantee: q + s with q on the triangle and |s| <= r is inside GrowObb(rect, r) and
// inside the union of the bounded exact offset's pieces, with no tolerance.
TEST(BoundingOffsetContainmentTest, TriangleGrownByBallIsInsideBothOffsets) {
  std::mt19937_64 rng(20240607);
  int64_t checks = 0, failures = 0;
  for (double scale : kScales) {
    for (double translation : kTranslations) {
      for (int repeat = 0; repeat < 2; ++repeat) {
        std::uniform_real_distribution<double> coordinate(-translation, translation);
        const Eigen::Vector3d base(coordinate(rng), coordinate(rng), coordinate(rng));
        for (const Triangle& t : test::TriangleFamilies(rng, scale, base)) {
          for (double r :
               {0.0, 1e-9 * scale, std::sqrt(3.0) * scale / 1024, scale, 10 * scale, 1e6 * scale}) {
            const Obb uobb = GrowObb(TriangleRectangle(t.a, t.b, t.c), r);
            const BoundedExactOffset offset = ComputeBoundedExactOffset(t.a, t.b, t.c, r);
            const auto points = test::TrianglePoints(rng, t, 12);
            const auto offsets = test::BallOffsets(rng, t, r, 6);
            for (const auto& q : points) {
              for (const auto& s : offsets) {
                const Eigen::Vector3d p = q + s;
                const bool in_uobb = test::InsideObb(uobb, p);
                const bool in_offset = test::InsideBoundedExactOffset(offset, p);
                ++checks;
                if (in_uobb && in_offset) continue;
                if (++failures <= 10) {
                  ADD_FAILURE() << t.kind << " scale " << scale << " translation " << translation
                                << " r " << r << " uobb " << in_uobb << " offset " << in_offset
                                << " s " << s.transpose();
                }
              }
            }
          }
        }
      }
    }
  }
  EXPECT_EQ(failures, 0) << "of " << checks;
  EXPECT_GT(checks, 1000000);
}

// The membership tests above are not vacuous: points well outside the offset are rejected.
TEST(BoundingOffsetContainmentTest, PointsFarOutsideAreRejected) {
  std::mt19937_64 rng(99);
  for (double scale : kScales) {
    for (double translation : kTranslations) {
      const Eigen::Vector3d base = translation * test::RandomDirection(rng);
      for (const Triangle& t : test::TriangleFamilies(rng, scale, base)) {
        const double r = 0.01 * scale;
        const Obb uobb = GrowObb(TriangleRectangle(t.a, t.b, t.c), r);
        const BoundedExactOffset offset = ComputeBoundedExactOffset(t.a, t.b, t.c, r);
        // Beyond every piece's reach: 2 r + slack along the frame's normal, from any point.
        const double far = 2 * r + 1e-12 * (scale + translation);
        const Eigen::Vector3d n = uobb.axes.col(2);
        for (const auto& q : test::TrianglePoints(rng, t, 4)) {
          EXPECT_FALSE(test::InsideObb(uobb, q + far * n)) << t.kind;
          EXPECT_FALSE(test::InsideBoundedExactOffset(offset, q - far * n)) << t.kind;
        }
      }
    }
  }
}

}  // namespace
}  // namespace far
