// Oriented boxes: corner numbering, the box triangles' orientation and closedness, growth,
// rigid motion and world AABBs.

#include <random>

#include <gtest/gtest.h>

#include "far/offsets/bounding_offset.h"
#include "far/offsets/offset_test_support.h"

namespace far {
namespace {

Obb RandomObb(std::mt19937_64& rng, double scale, double translation) {
  std::uniform_real_distribution<double> unit(0, 1);
  Obb box;
  box.center = translation * test::RandomDirection(rng);
  box.axes = test::RandomRotation(rng);
  box.half_extents = scale * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
  return box;
}

TEST(ObbTest, CornersFollowTheBitNumbering) {
  Obb box;
  box.center = Eigen::Vector3d(1, 2, 3);
  box.half_extents = Eigen::Vector3d(0.5, 1, 2);
  const auto corners = ObbCorners(box);
  EXPECT_EQ(corners[0], Eigen::Vector3d(0.5, 1, 1));
  EXPECT_EQ(corners[1], Eigen::Vector3d(1.5, 1, 1));
  EXPECT_EQ(corners[2], Eigen::Vector3d(0.5, 3, 1));
  EXPECT_EQ(corners[4], Eigen::Vector3d(0.5, 1, 5));
  EXPECT_EQ(corners[7], Eigen::Vector3d(1.5, 3, 5));
}

TEST(ObbTest, BoxTrianglesAreOutwardForRandomFrames) {
  std::mt19937_64 rng(1);
  std::vector<Obb> boxes;
  for (int trial = 0; trial < 100; ++trial) boxes.push_back(RandomObb(rng, 1, 10));
  // Frames as TriangleRectangle makes them, for both windings.
  for (int trial = 0; trial < 100; ++trial) {
    Eigen::Vector3d a = test::RandomInBall(rng, 1), b = test::RandomInBall(rng, 1),
                    c = test::RandomInBall(rng, 1);
    if (trial % 2) std::swap(b, c);
    boxes.push_back(GrowObb(TriangleRectangle(a, b, c), 0.1));
  }
  for (const Obb& box : boxes) {
    const auto corners = ObbCorners(box);
    for (size_t f = 0; f < kBoxTriangleCorners.size(); f += 3) {
      const auto& p0 = corners[kBoxTriangleCorners[f]];
      const auto& p1 = corners[kBoxTriangleCorners[f + 1]];
      const auto& p2 = corners[kBoxTriangleCorners[f + 2]];
      const Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0);
      EXPECT_GT(normal.dot((p0 + p1 + p2) / 3 - box.center), 0) << "face " << f / 3;
    }
  }
}

TEST(ObbTest, BoxTrianglesAreClosed) {
  int count[8][8] = {};
  for (size_t f = 0; f < kBoxTriangleCorners.size(); f += 3) {
    for (int k = 0; k < 3; ++k)
      ++count[kBoxTriangleCorners[f + k]][kBoxTriangleCorners[f + (k + 1) % 3]];
  }
  int edges = 0;
  for (int i = 0; i < 8; ++i) {
    for (int j = 0; j < 8; ++j) {
      EXPECT_LE(count[i][j], 1) << i << "->" << j;
      EXPECT_EQ(count[i][j], count[j][i]) << i << "->" << j;
      edges += count[i][j];
    }
  }
  EXPECT_EQ(edges, 36);  // 18 undirected edges: 12 box edges and 6 face diagonals
}

TEST(ObbTest, GrowObbAddsRRoundedUp) {
  std::mt19937_64 rng(2);
  for (int trial = 0; trial < 100; ++trial) {
    const Obb box = RandomObb(rng, 3, 100);
    const double r = 0.01 * trial;
    const Obb grown = GrowObb(box, r);
    EXPECT_EQ(grown.center, box.center);
    EXPECT_EQ(grown.axes, box.axes);
    for (int i = 0; i < 3; ++i) {
      EXPECT_GE(grown.half_extents[i], box.half_extents[i] + r);
      EXPECT_LE(grown.half_extents[i], (box.half_extents[i] + r) * (1 + 1e-13));
    }
  }
}

TEST(ObbTest, TransformMovesTheCorners) {
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 100; ++trial) {
    const Obb box_M = RandomObb(rng, 2, 5);
    Eigen::Isometry3d X_WM = Eigen::Isometry3d::Identity();
    X_WM.linear() = test::RandomRotation(rng);
    X_WM.translation() = 1e3 * test::RandomDirection(rng);
    const Obb box_W = TransformObb(X_WM, box_M);
    const auto corners_M = ObbCorners(box_M);
    const auto corners_W = ObbCorners(box_W);
    for (int k = 0; k < 8; ++k) {
      EXPECT_LE((corners_W[k] - X_WM * corners_M[k]).norm(), 1e-10) << k;
    }
    EXPECT_LE((box_W.axes.transpose() * box_W.axes - Eigen::Matrix3d::Identity()).norm(), 1e-14);
  }
}

TEST(ObbTest, AabbContainsTheCornersAndIsTight) {
  std::mt19937_64 rng(4);
  for (double translation : {0.0, 1.0, 1e6}) {
    for (double scale : {1e-6, 1.0, 1e6}) {
      for (int trial = 0; trial < 50; ++trial) {
        const Obb box = RandomObb(rng, scale, translation);
        const Eigen::AlignedBox3d aabb = ObbAabb(box);
        Eigen::AlignedBox3d exact;
        for (const auto& corner : ObbCorners(box)) {
          EXPECT_TRUE(aabb.contains(corner));
          exact.extend(corner);
        }
        EXPECT_LE((aabb.sizes() - exact.sizes()).maxCoeff(), 1e-12 * (scale + translation));
      }
    }
  }
  Obb point;  // zero extents at the origin: a point box
  EXPECT_TRUE(ObbAabb(point).contains(Eigen::Vector3d::Zero()));
}

}  // namespace
}  // namespace far
