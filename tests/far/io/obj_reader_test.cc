#include <string>

#include "io_test_util.h"
#include <gtest/gtest.h>

#include "far/io/mesh_io.h"

namespace far {
namespace {

using testing::IsError;
using testing::TempDir;
using testing::WriteFile;

constexpr const char* kSquare =
    "v 0 0 0\n"
    "v 1 0 0\n"
    "v 1 1 0\n"
    "v 0 1 0\n";

TEST(ObjReaderTest, ReadsVerticesAndTriangles) {
  const Result<Mesh> mesh = ReadObj("v 0 0 0\nv 1 0 0\nv 0 1.5 -2e-3\nf 1 2 3\n", "tri.obj");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  ASSERT_EQ(mesh->num_vertices(), 3);
  ASSERT_EQ(mesh->num_triangles(), 1);
  EXPECT_EQ(mesh->p_MV[2], Eigen::Vector3d(0, 1.5, -2e-3));
  EXPECT_EQ(mesh->triangles[0], (TriangleIndices{0, 1, 2}));
}

TEST(ObjReaderTest, FanTriangulatesPolygonsInFileOrder) {
  const std::string text = std::string(kSquare) +
                           "v 2 0 0\n"
                           "f 1 2 3\n"       // triangle 0
                           "f 1 2 3 4\n"     // triangles 1, 2
                           "f 5 4 3 2 1\n";  // triangles 3, 4, 5
  const Result<Mesh> mesh = ReadObj(text, "fan.obj");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  ASSERT_EQ(mesh->num_triangles(), 6);
  EXPECT_EQ(mesh->triangles[0], (TriangleIndices{0, 1, 2}));
  EXPECT_EQ(mesh->triangles[1], (TriangleIndices{0, 1, 2}));
  EXPECT_EQ(mesh->triangles[2], (TriangleIndices{0, 2, 3}));
  EXPECT_EQ(mesh->triangles[3], (TriangleIndices{4, 3, 2}));
  EXPECT_EQ(mesh->triangles[4], (TriangleIndices{4, 2, 1}));
  EXPECT_EQ(mesh->triangles[5], (TriangleIndices{4, 1, 0}));
}

TEST(ObjReaderTest, AcceptsEveryVertexReferenceForm) {
  const std::string text = std::string(kSquare) +
                           "vt 0 0\nvt 1 0\nvt 1 1\n"
                           "vn 0 0 1\n"
                           "f 1 2 3\n"
                           "f 1/1 2/2 3/3\n"
                           "f 1//1 2//1 3//1\n"
                           "f 1/1/1 3/3/1 4/2/1\n";
  const Result<Mesh> mesh = ReadObj(text, "forms.obj");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  ASSERT_EQ(mesh->num_triangles(), 4);
  EXPECT_EQ(mesh->triangles[2], (TriangleIndices{0, 1, 2}));
  EXPECT_EQ(mesh->triangles[3], (TriangleIndices{0, 2, 3}));
}

TEST(ObjReaderTest, ResolvesNegativeIndicesAgainstVerticesSoFar) {
  const std::string text =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
      "f -3 -2 -1\n"
      "v 5 5 5\n"
      "vt 0 0\nvn 0 0 1\n"
      "f -1/-1/-1 -4 -2//-1\n";
  const Result<Mesh> mesh = ReadObj(text, "neg.obj");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  ASSERT_EQ(mesh->num_triangles(), 2);
  EXPECT_EQ(mesh->triangles[0], (TriangleIndices{0, 1, 2}));
  EXPECT_EQ(mesh->triangles[1], (TriangleIndices{3, 0, 2}));
}

TEST(ObjReaderTest, IgnoresStatementsWithoutTriangleGeometry) {
  const std::string text =
      "# a comment\n"
      "mtllib leaf.mtl\n"
      "\n"
      "   \t \n"
      "o leaf\n"
      "g group one\n"
      "s off\n"
      "usemtl green\n"
      "v 0 0 0 # trailing comment\n"
      "v 1 0 0\n"
      "v 0 1 0\n"
      "vt 0.5 0.5\n"
      "vn 0 0 1\n"
      "vp 0.1 0.2\n"
      "l 1 2\n"
      "p 3\n"
      "mg 1 0.5\n"
      "f 1 2 3 # done\n";
  const Result<Mesh> mesh = ReadObj(text, "ignored.obj");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  EXPECT_EQ(mesh->num_vertices(), 3);
  EXPECT_EQ(mesh->num_triangles(), 1);
}

TEST(ObjReaderTest, IgnoresWeightAndVertexColors) {
  const Result<Mesh> mesh =
      ReadObj("v 0 0 0 1\nv 1 0 0 0.5\nv 0 1 0 0.2 0.3 0.4\nf 1 2 3\n", "w.obj");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  EXPECT_EQ(mesh->p_MV[1], Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(mesh->p_MV[2], Eigen::Vector3d(0, 1, 0));
}

TEST(ObjReaderTest, AcceptsCrlfByteOrderMarkTabsAndPlusSigns) {
  const Result<Mesh> mesh =
      ReadObj("\xEF\xBB\xBFv\t+1 0 0\r\nv 0 +1.5 0\r\nv 0 0 1e+2\r\nf\t1 2 3\r\n", "crlf.obj");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  EXPECT_EQ(mesh->p_MV[0], Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(mesh->p_MV[1], Eigen::Vector3d(0, 1.5, 0));
  EXPECT_EQ(mesh->p_MV[2], Eigen::Vector3d(0, 0, 100));
}

TEST(ObjReaderTest, KeepsUnusedVerticesSoIndicesMatchTheFile) {
  const Result<Mesh> mesh = ReadObj("v 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 2 3 4\n", "u.obj");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  EXPECT_EQ(mesh->num_vertices(), 4);
  EXPECT_EQ(mesh->triangles[0], (TriangleIndices{1, 2, 3}));
}

TEST(ObjReaderTest, ReadsFromFile) {
  TempDir dir;
  WriteFile(dir / "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const Result<Mesh> mesh = ReadObj(dir / "tri.obj");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  EXPECT_EQ(mesh->num_triangles(), 1);
}

// Errors: one per way a file can be wrong, each with its line.

TEST(ObjReaderTest, RejectsFaceIndexBeyondVertexCount) {
  const std::string text = std::string(kSquare) + "v 2 0 0\nv 2 1 0\nv 3 0 0\nv 3 1 0\n" +
                           "# line 9\n" + "v 4 0 0\n" + "\n" + "f 1 2 10\n";
  EXPECT_TRUE(IsError(ReadObj(text, "leaf.obj"), ErrorCode::kParseError,
                      "leaf.obj:12: face index 10 out of range (9 vertices)"));
  EXPECT_TRUE(IsError(ReadObj(std::string(kSquare) + "f 1 2 5\n", "leaf.obj"),
                      ErrorCode::kParseError,
                      "leaf.obj:5: face index 5 out of range (4 vertices)"));
}

TEST(ObjReaderTest, RejectsForwardReferences) {
  EXPECT_TRUE(IsError(ReadObj("v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n", "fwd.obj"),
                      ErrorCode::kParseError, "fwd.obj:3: face index 3 out of range (2 vertices)"));
}

TEST(ObjReaderTest, RejectsNegativeIndexBeforeFirstVertex) {
  EXPECT_TRUE(IsError(ReadObj(std::string(kSquare) + "f -1 -2 -5\n", "n.obj"),
                      ErrorCode::kParseError, "n.obj:5: face index -5 out of range (4 vertices)"));
}

TEST(ObjReaderTest, RejectsIndexZero) {
  EXPECT_TRUE(IsError(ReadObj(std::string(kSquare) + "f 0 1 2\n", "z.obj"), ErrorCode::kParseError,
                      "z.obj:5: face index 0 is invalid (OBJ indices start at 1)"));
}

TEST(ObjReaderTest, RejectsTextureAndNormalIndicesOutOfRange) {
  EXPECT_TRUE(IsError(ReadObj(std::string(kSquare) + "vt 0 0\nf 1/1 2/2 3/1\n", "t.obj"),
                      ErrorCode::kParseError,
                      "t.obj:6: texture coordinate index 2 out of range (1 texture coordinates)"));
  EXPECT_TRUE(IsError(ReadObj(std::string(kSquare) + "f 1//1 2//1 3//1\n", "n.obj"),
                      ErrorCode::kParseError, "n.obj:5: normal index 1 out of range (0 normals)"));
  EXPECT_TRUE(IsError(ReadObj(std::string(kSquare) + "vn 0 0 1\nf 1/0/1 2 3\n", "n.obj"),
                      ErrorCode::kParseError, "texture coordinate index 0 is invalid"));
}

TEST(ObjReaderTest, RejectsMalformedVertexReferences) {
  for (const char* reference : {"1/", "1/1/", "/1", "1/2/3/4", "1///2", "//"}) {
    const std::string text =
        std::string(kSquare) + "vt 0 0\nvt 0 0\nvn 0 0 1\nf 1 2 " + reference + "\n";
    EXPECT_TRUE(IsError(ReadObj(text, "r.obj"), ErrorCode::kParseError,
                        "r.obj:8: bad vertex reference '" + std::string(reference) + "'"))
        << reference;
  }
}

TEST(ObjReaderTest, RejectsNonIntegerFaceIndices) {
  EXPECT_TRUE(IsError(ReadObj(std::string(kSquare) + "f 1 2 x\n", "i.obj"), ErrorCode::kParseError,
                      "i.obj:5: face index 'x' is not an integer"));
  EXPECT_TRUE(IsError(ReadObj(std::string(kSquare) + "f 1 2 3.0\n", "i.obj"),
                      ErrorCode::kParseError, "face index '3.0' is not an integer"));
  EXPECT_TRUE(IsError(ReadObj(std::string(kSquare) + "f 1 2 99999999999999999999\n", "i.obj"),
                      ErrorCode::kParseError, "is not an integer"));
}

TEST(ObjReaderTest, RejectsFacesWithFewerThanThreeVertices) {
  EXPECT_TRUE(IsError(ReadObj(std::string(kSquare) + "f 1 2\n", "f.obj"), ErrorCode::kParseError,
                      "f.obj:5: face has 2 vertices (need at least 3)"));
  EXPECT_TRUE(IsError(ReadObj(std::string(kSquare) + "f\n", "f.obj"), ErrorCode::kParseError,
                      "f.obj:5: face has 0 vertices"));
}

TEST(ObjReaderTest, RejectsMissingCoordinates) {
  EXPECT_TRUE(IsError(ReadObj("v 1 2\nv 0 0 0\nv 1 1 1\nf 1 2 3\n", "c.obj"),
                      ErrorCode::kParseError,
                      "c.obj:1: vertex has 2 coordinates (expected x y z [w])"));
  EXPECT_TRUE(IsError(ReadObj("v\n", "c.obj"), ErrorCode::kParseError, "vertex has 0 coordinates"));
}

TEST(ObjReaderTest, RejectsWrongNumberOfVertexValues) {
  EXPECT_TRUE(IsError(ReadObj("v 1 2 3 4 5\n", "c.obj"), ErrorCode::kParseError,
                      "c.obj:1: vertex has 5 values"));
  EXPECT_TRUE(IsError(ReadObj("v 1 2 3 4 5 6 7\n", "c.obj"), ErrorCode::kParseError,
                      "c.obj:1: vertex has too many values"));
}

TEST(ObjReaderTest, RejectsGarbageNumbers) {
  for (const char* value : {"x", "1.0.0", "1e", "--1", "1,5", "0x10", "3abc"}) {
    const std::string text = "v 0 0 0\nv 1 " + std::string(value) + " 0\n";
    EXPECT_TRUE(IsError(ReadObj(text, "g.obj"), ErrorCode::kParseError,
                        "g.obj:2: vertex value '" + std::string(value) + "' is not a number"))
        << value;
  }
}

TEST(ObjReaderTest, RejectsNonFiniteCoordinates) {
  for (const char* value : {"nan", "inf", "-inf", "NaN", "infinity"}) {
    const std::string text = "v 0 0 0\nv 1 0 0\nv 0 " + std::string(value) + " 0\nf 1 2 3\n";
    EXPECT_TRUE(IsError(ReadObj(text, "nf.obj"), ErrorCode::kParseError,
                        "nf.obj:3: vertex value '" + std::string(value) + "' is not finite"))
        << value;
  }
  EXPECT_TRUE(IsError(ReadObj("v 1e999 0 0\n", "big.obj"), ErrorCode::kParseError,
                      "big.obj:1: vertex value '1e999' is out of double range"));
}

TEST(ObjReaderTest, RejectsUnknownStatements) {
  EXPECT_TRUE(IsError(ReadObj(std::string(kSquare) + "vx 1 2 3\n", "u.obj"), ErrorCode::kParseError,
                      "u.obj:5: unknown statement 'vx'"));
  EXPECT_TRUE(IsError(ReadObj("\x01\x02garbage\n", "bin.obj"), ErrorCode::kParseError,
                      "bin.obj:1: unknown statement '??garbage'"));
}

TEST(ObjReaderTest, RejectsFreeFormGeometry) {
  EXPECT_TRUE(IsError(ReadObj(std::string(kSquare) + "cstype bspline\ncurv 0 1 1 2\n", "ff.obj"),
                      ErrorCode::kParseError,
                      "ff.obj:5: free-form geometry statement 'cstype' is not supported"));
}

TEST(ObjReaderTest, RejectsLineContinuation) {
  EXPECT_TRUE(IsError(ReadObj(std::string(kSquare) + "f 1 2 \\\n3\n", "lc.obj"),
                      ErrorCode::kParseError, "lc.obj:5: line continuation"));
}

TEST(ObjReaderTest, RejectsFilesWithoutTriangles) {
  EXPECT_TRUE(IsError(ReadObj("", "e.obj"), ErrorCode::kParseError, "e.obj: no triangles"));
  EXPECT_TRUE(IsError(ReadObj(kSquare, "e.obj"), ErrorCode::kParseError,
                      "e.obj: no triangles (4 vertices, no faces)"));
  EXPECT_TRUE(IsError(ReadObj("# only a comment\nl 1 2\n", "e.obj"), ErrorCode::kParseError,
                      "no triangles"));
}

TEST(ObjReaderTest, ReportsMissingFileAsIoError) {
  TempDir dir;
  EXPECT_TRUE(
      IsError(ReadObj(dir / "missing.obj"), ErrorCode::kIoError, "missing.obj: cannot open"));
}

}  // namespace
}  // namespace far
