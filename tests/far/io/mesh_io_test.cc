#include "far/io/mesh_io.h"

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "io_test_util.h"
#include <gtest/gtest.h>

namespace far {
namespace {

using testing::IsError;
using testing::ReadFile;
using testing::SameMesh;
using testing::TempDir;
using testing::WriteFile;

// A random mesh with awkward doubles (tiny, huge, negative, non-representable decimals).
Mesh RandomMesh(uint32_t seed, int num_vertices, int num_triangles) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-30, 30);
  std::uniform_int_distribution<uint32_t> index(0, static_cast<uint32_t>(num_vertices - 1));
  Mesh mesh;
  for (int v = 0; v < num_vertices; ++v) {
    Eigen::Vector3d p;
    for (int axis = 0; axis < 3; ++axis) p[axis] = unit(random) * std::pow(10.0, exponent(random));
    mesh.p_MV.push_back(p);
  }
  for (int t = 0; t < num_triangles; ++t)
    mesh.triangles.push_back({index(random), index(random), index(random)});
  return mesh;
}

// Rounds to float32 through memory. GCC 12.2 at -O2 dropped the rounding of
// p.cast<float>().cast<double>() in this test (fixed by -fno-tree-slp-vectorize; not reduced).
double RoundToFloat(double value) {
  volatile float rounded = static_cast<float>(value);
  return rounded;
}

Mesh Tetrahedron() {
  Mesh mesh;
  mesh.p_MV = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return mesh;
}

TEST(MeshIoTest, ReadMeshDispatchesOnExtensionIgnoringCase) {
  TempDir dir;
  const Mesh mesh = Tetrahedron();
  for (const char* name : {"a.obj", "b.OBJ", "c.ply", "d.Ply", "e.stl", "f.STL"}) {
    ASSERT_TRUE(WriteMesh(mesh, dir / name).ok()) << name;
    const Result<Mesh> read = ReadMesh(dir / name);
    ASSERT_TRUE(read.ok()) << name << ": " << ToString(read.error());
    EXPECT_EQ(read->num_triangles(), 4) << name;
  }
  // The content decides nothing: OBJ text in a .ply file is a PLY error.
  WriteFile(dir / "wrong.ply", "v 0 0 0\n");
  EXPECT_TRUE(IsError(ReadMesh(dir / "wrong.ply"), ErrorCode::kParseError, "not a PLY file"));
}

TEST(MeshIoTest, RejectsUnknownExtensions) {
  TempDir dir;
  WriteFile(dir / "mesh.off", "OFF\n");
  EXPECT_TRUE(IsError(ReadMesh(dir / "mesh.off"), ErrorCode::kInvalidArgument,
                      "unknown mesh file extension '.off' (expected .obj, .ply or .stl)"));
  EXPECT_TRUE(IsError(ReadMesh(dir / "noextension"), ErrorCode::kInvalidArgument,
                      "unknown mesh file extension ''"));
  EXPECT_TRUE(IsError(WriteMesh(Tetrahedron(), dir / "mesh.gltf"), ErrorCode::kInvalidArgument,
                      "unknown mesh file extension '.gltf'"));
}

TEST(MeshIoTest, ReportsUnreadableFilesAsIoErrors) {
  TempDir dir;
  EXPECT_TRUE(IsError(ReadMesh(dir / "missing.obj"), ErrorCode::kIoError,
                      (dir / "missing.obj").string() + ": cannot open for reading"));
  std::filesystem::create_directories(dir / "folder.stl");
  EXPECT_TRUE(IsError(ReadMesh(dir / "folder.stl"), ErrorCode::kIoError, "is a directory"));
}

TEST(MeshIoTest, ObjRoundTripIsExact) {
  TempDir dir;
  for (uint32_t seed = 1; seed <= 5; ++seed) {
    const Mesh mesh = RandomMesh(seed, 50, 80);
    ASSERT_TRUE(WriteObj(mesh, dir / "r.obj").ok());
    const Result<Mesh> read = ReadObj(dir / "r.obj");
    ASSERT_TRUE(read.ok()) << ToString(read.error());
    EXPECT_TRUE(SameMesh(*read, mesh)) << "seed " << seed;
  }
}

TEST(MeshIoTest, PlyRoundTripIsExact) {
  TempDir dir;
  for (uint32_t seed = 1; seed <= 5; ++seed) {
    const Mesh mesh = RandomMesh(seed, 50, 80);
    ASSERT_TRUE(WritePly(mesh, dir / "r.ply").ok());
    const Result<Mesh> read = ReadPly(dir / "r.ply");
    ASSERT_TRUE(read.ok()) << ToString(read.error());
    EXPECT_TRUE(SameMesh(*read, mesh)) << "seed " << seed;
  }
}

TEST(MeshIoTest, StlRoundTripGivesThreeFloatVerticesPerTriangle) {
  TempDir dir;
  const Mesh mesh = RandomMesh(7, 20, 30);
  ASSERT_TRUE(WriteStl(mesh, dir / "r.stl").ok());
  EXPECT_EQ(std::filesystem::file_size(dir / "r.stl"), 84u + 50u * 30u);
  const Result<Mesh> read = ReadStl(dir / "r.stl");
  ASSERT_TRUE(read.ok()) << ToString(read.error());
  ASSERT_EQ(read->num_triangles(), 30);
  ASSERT_EQ(read->num_vertices(), 90);
  for (int t = 0; t < 30; ++t) {
    EXPECT_EQ(read->triangles[t],
              (TriangleIndices{uint32_t(3 * t), uint32_t(3 * t + 1), uint32_t(3 * t + 2)}));
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p_MV = mesh.p_MV[mesh.triangles[t][k]];
      const Eigen::Vector3d expected(RoundToFloat(p_MV.x()), RoundToFloat(p_MV.y()),
                                     RoundToFloat(p_MV.z()));
      EXPECT_EQ(read->p_MV[3 * t + k], expected) << "triangle " << t << " vertex " << k;
    }
  }
}

TEST(MeshIoTest, WritersRejectInvalidMeshes) {
  TempDir dir;
  Mesh empty;
  empty.p_MV = {{0, 0, 0}};
  Mesh bad_index = Tetrahedron();
  bad_index.triangles[2][1] = 4;
  Mesh not_finite = Tetrahedron();
  not_finite.p_MV[3].y() = std::numeric_limits<double>::quiet_NaN();
  for (const char* name : {"m.obj", "m.ply", "m.stl"}) {
    EXPECT_TRUE(IsError(WriteMesh(empty, dir / name), ErrorCode::kInvalidArgument,
                        "cannot write mesh: no triangles"));
    EXPECT_TRUE(IsError(WriteMesh(bad_index, dir / name), ErrorCode::kInvalidArgument,
                        "triangle 2: vertex index 4 out of range (4 vertices)"));
    EXPECT_TRUE(IsError(WriteMesh(not_finite, dir / name), ErrorCode::kInvalidArgument,
                        "vertex 3 has a non-finite coordinate"));
    EXPECT_FALSE(std::filesystem::exists(dir / name)) << name;
  }
}

TEST(MeshIoTest, StlWriterRejectsCoordinatesBeyondFloat) {
  TempDir dir;
  Mesh mesh = Tetrahedron();
  mesh.p_MV[1].x() = 1e39;
  EXPECT_TRUE(IsError(WriteStl(mesh, dir / "big.stl"), ErrorCode::kInvalidArgument,
                      "vertex 1 does not fit in float32"));
}

TEST(MeshIoTest, WritersReportUnwritablePaths) {
  TempDir dir;
  EXPECT_TRUE(IsError(WriteObj(Tetrahedron(), dir / "no" / "such" / "dir.obj"), ErrorCode::kIoError,
                      "cannot open for writing"));
}

TEST(MeshIoTest, ValidateMeshAcceptsDegenerateTriangles) {
  Mesh mesh;
  mesh.p_MV = {{0, 0, 0}, {0, 0, 0}};
  mesh.triangles = {{0, 0, 1}};
  EXPECT_TRUE(ValidateMesh(mesh).ok());
}

// Robustness: every strict prefix of a binary PLY or STL file is an error (never a partial
// mesh), and random byte damage to any file gives either an error or a valid mesh.

TEST(MeshIoTest, EveryTruncationOfBinaryFilesIsAnError) {
  TempDir dir;
  const Mesh mesh = RandomMesh(3, 6, 5);
  ASSERT_TRUE(WritePly(mesh, dir / "m.ply").ok());
  ASSERT_TRUE(WriteStl(mesh, dir / "m.stl").ok());
  const std::string ply = ReadFile(dir / "m.ply");
  const std::string stl = ReadFile(dir / "m.stl");
  for (size_t size = 0; size < ply.size(); ++size) {
    ASSERT_FALSE(ReadPly(std::string_view(ply).substr(0, size), "cut.ply").ok()) << size;
  }
  for (size_t size = 0; size < stl.size(); ++size) {
    ASSERT_FALSE(ReadStl(std::string_view(stl).substr(0, size), "cut.stl").ok()) << size;
  }
}

TEST(MeshIoTest, DamagedFilesGiveAnErrorOrAValidMesh) {
  TempDir dir;
  const Mesh mesh = RandomMesh(11, 8, 10);
  ASSERT_TRUE(WriteObj(mesh, dir / "m.obj").ok());
  ASSERT_TRUE(WritePly(mesh, dir / "m.ply").ok());
  ASSERT_TRUE(WriteStl(mesh, dir / "m.stl").ok());
  std::mt19937 random(42);
  for (const char* name : {"m.obj", "m.ply", "m.stl"}) {
    const std::string original = ReadFile(dir / name);
    std::uniform_int_distribution<size_t> position(0, original.size() - 1);
    std::uniform_int_distribution<int> byte(0, 255);
    int errors = 0;
    for (int trial = 0; trial < 2000; ++trial) {
      std::string damaged = original;
      const int flips = 1 + trial % 4;
      for (int i = 0; i < flips; ++i) damaged[position(random)] = static_cast<char>(byte(random));
      const std::string_view extension = std::string_view(name).substr(2);
      const Result<Mesh> read = extension == "obj"   ? ReadObj(damaged, name)
                                : extension == "ply" ? ReadPly(damaged, name)
                                                     : ReadStl(damaged, name);
      if (read.ok()) {
        ASSERT_TRUE(ValidateMesh(*read).ok()) << name << " trial " << trial;
      } else {
        ++errors;
        ASSERT_EQ(read.error().message.rfind(name, 0), 0u) << read.error().message;
      }
    }
    EXPECT_GT(errors, 0) << name;
  }
}

}  // namespace
}  // namespace far
