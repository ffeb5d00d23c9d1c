#include <limits>
#include <string>
#include <vector>

#include "io_test_util.h"
#include <gtest/gtest.h>

#include "far/io/mesh_io.h"

namespace far {
namespace {

using testing::Bytes;
using testing::IsError;
using testing::TempDir;
using testing::WriteFile;

// A binary STL of `triangles` (each three vertices), with `header` padded to 80 bytes.
std::string BinaryStl(const std::vector<std::array<Eigen::Vector3f, 3>>& triangles,
                      std::string header = "binary test", int64_t count = -1) {
  header.resize(80, ' ');
  Bytes bytes;
  bytes.Text(header).Put<uint32_t>(
      static_cast<uint32_t>(count >= 0 ? count : static_cast<int64_t>(triangles.size())));
  for (const auto& triangle : triangles) {
    bytes.Put<float>(0).Put<float>(0).Put<float>(1);  // normal, ignored
    for (const Eigen::Vector3f& p : triangle)
      bytes.Put<float>(p.x()).Put<float>(p.y()).Put<float>(p.z());
    bytes.Put<uint16_t>(0);
  }
  return bytes.str();
}

const std::vector<std::array<Eigen::Vector3f, 3>> kTwoTriangles = {
    {Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(1, 1, 0)},
    {Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 1, 0), Eigen::Vector3f(0, 1, 0.5f)}};

TEST(StlReaderTest, ReadsBinaryWithThreeUnweldedVerticesPerFacet) {
  const Result<Mesh> mesh = ReadStl(BinaryStl(kTwoTriangles), "part.stl");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  ASSERT_EQ(mesh->num_vertices(), 6);
  ASSERT_EQ(mesh->num_triangles(), 2);
  EXPECT_EQ(mesh->triangles[0], (TriangleIndices{0, 1, 2}));
  EXPECT_EQ(mesh->triangles[1], (TriangleIndices{3, 4, 5}));
  EXPECT_EQ(mesh->p_MV[3], Eigen::Vector3d(0, 0, 0));  // shared corner, not welded
  EXPECT_EQ(mesh->p_MV[5], Eigen::Vector3d(0, 1, 0.5));
}

TEST(StlReaderTest, ReadsBinaryWhoseHeaderStartsWithSolid) {
  // Many binary exporters write "solid" into the header: the size rule decides.
  const Result<Mesh> mesh = ReadStl(BinaryStl(kTwoTriangles, "solid part made by CAD"), "s.stl");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  EXPECT_EQ(mesh->num_triangles(), 2);
}

constexpr const char* kAsciiTwo =
    "solid square\n"
    "  facet normal 0 0 1\n"
    "    outer loop\n"
    "      vertex 0 0 0\n"
    "      vertex 1 0 0\n"
    "      vertex 1 1 0\n"
    "    endloop\n"
    "  endfacet\n"
    "  facet normal 0 0 1\n"
    "    outer loop\n"
    "      vertex 0 0 0\n"
    "      vertex 1 1 0\n"
    "      vertex 0 1 0.5\n"
    "    endloop\n"
    "  endfacet\n"
    "endsolid square\n";

TEST(StlReaderTest, ReadsAscii) {
  const Result<Mesh> ascii = ReadStl(kAsciiTwo, "a.stl");
  ASSERT_TRUE(ascii.ok()) << ToString(ascii.error());
  const Result<Mesh> binary = ReadStl(BinaryStl(kTwoTriangles), "b.stl");
  ASSERT_TRUE(binary.ok());
  EXPECT_TRUE(testing::SameMesh(*ascii, *binary));
}

TEST(StlReaderTest, ReadsAsciiVariants) {
  // Upper case, CRLF, tabs, no names, several solids, a NaN normal (normals are ignored).
  const std::string text =
      "SOLID\r\n"
      "FACET NORMAL nan nan nan\r\n OUTER LOOP\r\n"
      "\tVERTEX 0 0 0\r\n\tVERTEX 1 0 0\r\n\tVERTEX 0 1 0\r\n ENDLOOP\r\nENDFACET\r\n"
      "ENDSOLID\r\n"
      "solid second\n"
      "facet normal 0 0 1 outer loop vertex 0 0 1 vertex 1 0 1 vertex 0 1 1 endloop endfacet\n"
      "endsolid second\n\n";
  const Result<Mesh> mesh = ReadStl(text, "v.stl");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  ASSERT_EQ(mesh->num_triangles(), 2);
  EXPECT_EQ(mesh->p_MV[5], Eigen::Vector3d(0, 1, 1));
}

TEST(StlReaderTest, ReadsFromFile) {
  TempDir dir;
  WriteFile(dir / "a.stl", kAsciiTwo);
  const Result<Mesh> mesh = ReadStl(dir / "a.stl");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  EXPECT_EQ(mesh->num_triangles(), 2);
}

// Binary errors, with byte offsets.

TEST(StlReaderTest, RejectsBinaryTruncatedBelowHeaderCount) {
  std::string bytes = BinaryStl(kTwoTriangles, "binary", 10);
  bytes += std::string(50, '\0');  // room for 3 facets in all
  EXPECT_TRUE(
      IsError(ReadStl(bytes, "part.stl"), ErrorCode::kParseError,
              "part.stl: byte 84: truncated: header says 10 triangles, file has room for 3"));
}

TEST(StlReaderTest, RejectsHostileBinaryCountWithoutAllocating) {
  const std::string bytes = BinaryStl({}, "binary", 0xffffffffll);
  EXPECT_TRUE(
      IsError(ReadStl(bytes, "h.stl"), ErrorCode::kParseError,
              "h.stl: byte 84: truncated: header says 4294967295 triangles, file has room for 0"));
}

TEST(StlReaderTest, RejectsBinaryWithExtraBytes) {
  std::string bytes = BinaryStl(kTwoTriangles, "binary", 1);
  EXPECT_TRUE(IsError(ReadStl(bytes, "x.stl"), ErrorCode::kParseError,
                      "x.stl: byte 134: header says 1 triangles, but 50 more bytes follow them"));
}

TEST(StlReaderTest, RejectsBinaryWithZeroTriangles) {
  EXPECT_TRUE(
      IsError(ReadStl(BinaryStl({}), "z.stl"), ErrorCode::kParseError, "z.stl: no triangles"));
}

TEST(StlReaderTest, RejectsBinaryNonFiniteCoordinate) {
  auto triangles = kTwoTriangles;
  triangles[1][2].y() = std::numeric_limits<float>::quiet_NaN();
  // Facet 1 starts at 84 + 50; vertex 2 at +12 + 24; y at +4.
  EXPECT_TRUE(IsError(ReadStl(BinaryStl(triangles), "n.stl"), ErrorCode::kParseError,
                      "n.stl: byte " + std::to_string(84 + 50 + 36 + 4) +
                          ": triangle 1 vertex 2: coordinate y is not finite"));
  triangles[1][2].y() = -std::numeric_limits<float>::infinity();
  EXPECT_TRUE(IsError(ReadStl(BinaryStl(triangles), "n.stl"), ErrorCode::kParseError,
                      "coordinate y is not finite (-inf)"));
}

TEST(StlReaderTest, RejectsTinyFilesThatAreNotAscii) {
  EXPECT_TRUE(
      IsError(ReadStl("", "e.stl"), ErrorCode::kParseError, "e.stl: byte 0: not an STL file"));
  EXPECT_TRUE(IsError(ReadStl("hello", "e.stl"), ErrorCode::kParseError, "not an STL file"));
}

TEST(StlReaderTest, TreatsTruncatedBinaryStartingWithSolidAsBinary) {
  // Not text (float bytes), so the size error is reported, not a confusing ascii one.
  std::string bytes = BinaryStl(kTwoTriangles, "solid cad export");
  bytes.resize(bytes.size() - 10);
  EXPECT_TRUE(IsError(ReadStl(bytes, "c.stl"), ErrorCode::kParseError,
                      "c.stl: byte 84: truncated: header says 2 triangles, file has room for 1"));
}

// Ascii errors, with lines.

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(StlReaderTest, RejectsAsciiMissingEndsolid) {
  EXPECT_TRUE(IsError(ReadStl(Replace(kAsciiTwo, "endsolid square\n", ""), "a.stl"),
                      ErrorCode::kParseError, "a.stl:16: truncated: file ends before 'endsolid'"));
}

TEST(StlReaderTest, RejectsAsciiUnexpectedKeywords) {
  EXPECT_TRUE(IsError(
      ReadStl(Replace(kAsciiTwo, "facet normal 0 0 1\n    outer", "facet normal 0 0 1\n    inner"),
              "a.stl"),
      ErrorCode::kParseError, "a.stl:3: expected 'outer', got 'inner'"));
  EXPECT_TRUE(IsError(
      ReadStl(Replace(kAsciiTwo, "  facet normal 0 0 1\n", "  facett normal 0 0 1\n"), "a.stl"),
      ErrorCode::kParseError, "a.stl:2: expected 'facet' or 'endsolid', got 'facett'"));
  EXPECT_TRUE(IsError(ReadStl(Replace(kAsciiTwo, "facet normal", "facet"), "a.stl"),
                      ErrorCode::kParseError, "a.stl:2: expected 'normal', got '0'"));
}

TEST(StlReaderTest, RejectsAsciiFacetsWithoutExactlyThreeVertices) {
  EXPECT_TRUE(IsError(
      ReadStl(Replace(kAsciiTwo, "      vertex 1 1 0\n    endloop", "    endloop"), "a.stl"),
      ErrorCode::kParseError, "a.stl:6: expected 'vertex', got 'endloop'"));
  EXPECT_TRUE(IsError(ReadStl(Replace(kAsciiTwo, "      vertex 1 1 0\n    endloop",
                                      "      vertex 1 1 0\n      vertex 2 2 2\n    endloop"),
                              "a.stl"),
                      ErrorCode::kParseError, "a.stl:7: expected 'endloop', got 'vertex'"));
}

TEST(StlReaderTest, RejectsAsciiBadNumbers) {
  EXPECT_TRUE(IsError(ReadStl(Replace(kAsciiTwo, "vertex 1 0 0", "vertex 1 zero 0"), "a.stl"),
                      ErrorCode::kParseError, "a.stl:5: vertex: 'zero' is not a number"));
  EXPECT_TRUE(IsError(ReadStl(Replace(kAsciiTwo, "vertex 1 0 0", "vertex 1 0"), "a.stl"),
                      ErrorCode::kParseError, "a.stl:6: vertex: 'vertex' is not a number"));
  EXPECT_TRUE(IsError(ReadStl(Replace(kAsciiTwo, "normal 0 0 1", "normal 0 x 1"), "a.stl"),
                      ErrorCode::kParseError, "a.stl:2: normal: 'x' is not a number"));
  EXPECT_TRUE(IsError(ReadStl(Replace(kAsciiTwo, "vertex 1 0 0", "vertex 1 0 1e400"), "a.stl"),
                      ErrorCode::kParseError, "a.stl:5: vertex: '1e400' is out of double range"));
  EXPECT_TRUE(IsError(ReadStl("solid x\nfacet normal 0 0 1 outer loop vertex 1 2", "a.stl"),
                      ErrorCode::kParseError, "a.stl:2: vertex: file ends inside the coordinates"));
}

TEST(StlReaderTest, RejectsAsciiNonFiniteVertices) {
  EXPECT_TRUE(IsError(ReadStl(Replace(kAsciiTwo, "vertex 0 1 0.5", "vertex 0 inf 0.5"), "a.stl"),
                      ErrorCode::kParseError, "a.stl:13: vertex: coordinate 'inf' is not finite"));
  EXPECT_TRUE(IsError(ReadStl(Replace(kAsciiTwo, "vertex 0 1 0.5", "vertex 0 1 NaN"), "a.stl"),
                      ErrorCode::kParseError, "a.stl:13: vertex: coordinate 'NaN' is not finite"));
}

TEST(StlReaderTest, RejectsAsciiDataAfterEndsolid) {
  EXPECT_TRUE(IsError(ReadStl(std::string(kAsciiTwo) + "garbage\n", "a.stl"),
                      ErrorCode::kParseError, "a.stl:17: unexpected 'garbage' after 'endsolid'"));
}

TEST(StlReaderTest, RejectsAsciiWithoutFacets) {
  EXPECT_TRUE(IsError(ReadStl("solid empty\nendsolid empty\n", "a.stl"), ErrorCode::kParseError,
                      "a.stl: no triangles"));
}

TEST(StlReaderTest, ReportsMissingFileAsIoError) {
  TempDir dir;
  EXPECT_TRUE(IsError(ReadStl(dir / "none.stl"), ErrorCode::kIoError, "none.stl: cannot open"));
}

}  // namespace
}  // namespace far
