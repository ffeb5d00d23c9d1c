#include <chrono>
#include <string>

#include "io_test_util.h"
#include <gtest/gtest.h>

#include "far/io/mesh_io.h"

namespace far {
namespace {

using testing::Bytes;
using testing::IsError;
using testing::SameMesh;
using testing::TempDir;
using testing::WriteFile;

// The unit square as two triangles in every test: vertices 0..3, one quad face (fan 0 1 2, 0 2 3).
Mesh Square() {
  Mesh mesh;
  mesh.p_MV = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  return mesh;
}

constexpr const char* kAsciiSquare =
    "ply\n"
    "format ascii 1.0\n"
    "comment a square\n"
    "element vertex 4\n"
    "property float x\n"
    "property float y\n"
    "property float z\n"
    "element face 1\n"
    "property list uchar int vertex_indices\n"
    "end_header\n"
    "0 0 0\n"
    "1 0 0\n"
    "1 1 0\n"
    "0 1 0\n"
    "4 0 1 2 3\n";

TEST(PlyReaderTest, ReadsAsciiAndFanTriangulates) {
  const Result<Mesh> mesh = ReadPly(kAsciiSquare, "sq.ply");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  EXPECT_TRUE(SameMesh(*mesh, Square()));
}

TEST(PlyReaderTest, ReadsAsciiWithExtraPropertiesElementsAndCrlf) {
  const std::string text =
      "ply\r\n"
      "format ascii 1.0\r\n"
      "obj_info made by hand\r\n"
      "element material 1\r\n"
      "property uchar red\r\n"
      "property list uint8 float weights\r\n"
      "element vertex 4\r\n"
      "property double nx\r\n"
      "property int z\r\n"
      "property list ushort short tags\r\n"
      "property float y\r\n"
      "property uchar x\r\n"
      "element face 2\r\n"
      "property int flags\r\n"
      "property list uint16 uint vertex_index\r\n"
      "property list uchar float texcoord\r\n"
      "end_header\r\n"
      "255 2 0.5 0.25\r\n"
      "0.1 0 0 0 0\r\n"
      "-1 0 2 7 -7 0 1\r\n"
      "+1e3 0 1 -3 1 1\r\n"
      "0 0 0 1 0\r\n"
      "\r\n"
      "0 3 0 1 2 6 0 0 1 0 1 1\r\n"
      "9 3 0 2 3 0\r\n"
      "\r\n";
  const Result<Mesh> mesh = ReadPly(text, "extra.ply");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  EXPECT_TRUE(SameMesh(*mesh, Square()));
}

// The square as binary PLY with x, y, z of type T (`type_name` in the header), mixed with
// properties, lists and elements the reader must skip.
template <typename T>
std::string BinarySquare(const char* type_name, bool big_endian) {
  Bytes bytes(big_endian);
  bytes.Text(std::string("ply\nformat ") +
             (big_endian ? "binary_big_endian" : "binary_little_endian") + " 1.0\n");
  bytes.Text("element vertex 4\n");
  bytes.Text(std::string("property ") + type_name + " x\n");
  bytes.Text("property uchar red\n");
  bytes.Text(std::string("property ") + type_name + " y\n");
  bytes.Text("property list uchar double extra\n");
  bytes.Text(std::string("property ") + type_name + " z\n");
  bytes.Text("element edge 1\nproperty int vertex1\nproperty int vertex2\n");
  bytes.Text("element face 2\nproperty list int ushort vertex_indices\nproperty float quality\n");
  bytes.Text("end_header\n");
  const int corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int v = 0; v < 4; ++v) {
    bytes.Put<T>(static_cast<T>(corners[v][0]));
    bytes.Put<uint8_t>(200);
    bytes.Put<T>(static_cast<T>(corners[v][1]));
    bytes.Put<uint8_t>(static_cast<uint8_t>(v));
    for (int k = 0; k < v; ++k) bytes.Put<double>(k);
    bytes.Put<T>(static_cast<T>(0));
  }
  bytes.Put<int32_t>(0).Put<int32_t>(1);
  bytes.Put<int32_t>(3).Put<uint16_t>(0).Put<uint16_t>(1).Put<uint16_t>(2).Put<float>(0.5f);
  bytes.Put<int32_t>(3).Put<uint16_t>(0).Put<uint16_t>(2).Put<uint16_t>(3).Put<float>(1.5f);
  return bytes.str();
}

TEST(PlyReaderTest, ReadsBinaryLittleAndBigEndianWithEveryScalarType) {
  for (const bool big_endian : {false, true}) {
    SCOPED_TRACE(big_endian ? "big endian" : "little endian");
    const std::string name = "bin.ply";
    auto check = [&](const std::string& bytes, const char* type) {
      const Result<Mesh> mesh = ReadPly(bytes, name);
      ASSERT_TRUE(mesh.ok()) << type << ": " << ToString(mesh.error());
      EXPECT_TRUE(SameMesh(*mesh, Square())) << type;
    };
    check(BinarySquare<int8_t>("char", big_endian), "char");
    check(BinarySquare<uint8_t>("uchar", big_endian), "uchar");
    check(BinarySquare<int16_t>("short", big_endian), "short");
    check(BinarySquare<uint16_t>("ushort", big_endian), "ushort");
    check(BinarySquare<int32_t>("int", big_endian), "int");
    check(BinarySquare<uint32_t>("uint", big_endian), "uint");
    check(BinarySquare<float>("float", big_endian), "float");
    check(BinarySquare<double>("double", big_endian), "double");
    check(BinarySquare<int8_t>("int8", big_endian), "int8");
    check(BinarySquare<uint8_t>("uint8", big_endian), "uint8");
    check(BinarySquare<int16_t>("int16", big_endian), "int16");
    check(BinarySquare<uint16_t>("uint16", big_endian), "uint16");
    check(BinarySquare<int32_t>("int32", big_endian), "int32");
    check(BinarySquare<uint32_t>("uint32", big_endian), "uint32");
    check(BinarySquare<float>("float32", big_endian), "float32");
    check(BinarySquare<double>("float64", big_endian), "float64");
  }
}

TEST(PlyReaderTest, ReadsBinaryDoublesExactly) {
  Bytes bytes;
  bytes.Text(
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\n"
      "property double y\nproperty double z\nelement face 1\n"
      "property list uchar uint vertex_indices\nend_header\n");
  const double values[9] = {0.1, -1e300, 5e-324, 1.0 / 3.0, 2, 3, 4, 5, 6};
  for (const double value : values) bytes.Put<double>(value);
  bytes.Put<uint8_t>(3).Put<uint32_t>(2).Put<uint32_t>(1).Put<uint32_t>(0);
  const Result<Mesh> mesh = ReadPly(bytes.str(), "d.ply");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  EXPECT_EQ(mesh->p_MV[0], Eigen::Vector3d(0.1, -1e300, 5e-324));
  EXPECT_EQ(mesh->triangles[0], (TriangleIndices{2, 1, 0}));
}

TEST(PlyReaderTest, ReadsFaceElementBeforeVertexElement) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
      "3 2 1 0\n0 0 0\n1 0 0\n0 1 0\n";
  const Result<Mesh> mesh = ReadPly(text, "order.ply");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  EXPECT_EQ(mesh->triangles[0], (TriangleIndices{2, 1, 0}));
  EXPECT_EQ(mesh->p_MV[1], Eigen::Vector3d(1, 0, 0));
}

TEST(PlyReaderTest, ReadsFromFile) {
  TempDir dir;
  WriteFile(dir / "sq.ply", kAsciiSquare);
  const Result<Mesh> mesh = ReadPly(dir / "sq.ply");
  ASSERT_TRUE(mesh.ok()) << ToString(mesh.error());
  EXPECT_TRUE(SameMesh(*mesh, Square()));
}

// Header errors, each naming its line.

std::string AsciiWithHeader(const std::string& header_lines, const std::string& body) {
  return "ply\nformat ascii 1.0\n" + header_lines + "end_header\n" + body;
}

constexpr const char* kVertexXyz =
    "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
constexpr const char* kFaceList = "element face 1\nproperty list uchar int vertex_indices\n";
constexpr const char* kTriangleBody = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

TEST(PlyReaderTest, RejectsWrongMagic) {
  EXPECT_TRUE(IsError(ReadPly("PLY\nformat ascii 1.0\n", "m.ply"), ErrorCode::kParseError,
                      "m.ply:1: not a PLY file"));
  EXPECT_TRUE(IsError(ReadPly("", "m.ply"), ErrorCode::kParseError, "m.ply: truncated header"));
}

TEST(PlyReaderTest, RejectsMissingEndHeader) {
  EXPECT_TRUE(IsError(ReadPly(std::string("ply\nformat ascii 1.0\n") + kVertexXyz, "h.ply"),
                      ErrorCode::kParseError, "h.ply: truncated header: no end_header line"));
}

TEST(PlyReaderTest, RejectsBadFormatLines) {
  EXPECT_TRUE(IsError(ReadPly("ply\nformat binary 1.0\n", "f.ply"), ErrorCode::kParseError,
                      "f.ply:2: unknown format 'binary'"));
  EXPECT_TRUE(IsError(ReadPly("ply\nformat ascii 2.0\n", "f.ply"), ErrorCode::kParseError,
                      "f.ply:2: unsupported PLY version '2.0'"));
  EXPECT_TRUE(IsError(ReadPly("ply\nformat ascii\n", "f.ply"), ErrorCode::kParseError,
                      "f.ply:2: expected 'format"));
  EXPECT_TRUE(IsError(ReadPly("ply\nformat ascii 1.0\nformat ascii 1.0\n", "f.ply"),
                      ErrorCode::kParseError, "f.ply:3: second format line"));
  EXPECT_TRUE(IsError(ReadPly(std::string("ply\n") + kVertexXyz, "f.ply"), ErrorCode::kParseError,
                      "f.ply:2: element before the format line"));
  EXPECT_TRUE(IsError(ReadPly("ply\nend_header\n", "f.ply"), ErrorCode::kParseError,
                      "f.ply:2: end_header before the format line"));
}

TEST(PlyReaderTest, RejectsUnknownHeaderKeywordsAndTypes) {
  EXPECT_TRUE(IsError(ReadPly(AsciiWithHeader("elemnt vertex 3\n", ""), "k.ply"),
                      ErrorCode::kParseError, "k.ply:3: unknown header keyword 'elemnt'"));
  EXPECT_TRUE(
      IsError(ReadPly(AsciiWithHeader("element vertex 3\nproperty float64x x\n", ""), "k.ply"),
              ErrorCode::kParseError, "k.ply:4: unknown type 'float64x'"));
  EXPECT_TRUE(IsError(
      ReadPly(AsciiWithHeader("element face 1\nproperty list uchar long vertex_indices\n", ""),
              "k.ply"),
      ErrorCode::kParseError, "k.ply:4: unknown type 'long'"));
  EXPECT_TRUE(IsError(ReadPly(AsciiWithHeader("element vertex 3\nproperty float\n", ""), "k.ply"),
                      ErrorCode::kParseError, "k.ply:4: expected 'property <type> <name>'"));
  EXPECT_TRUE(IsError(ReadPly(AsciiWithHeader("element vertex\n", ""), "k.ply"),
                      ErrorCode::kParseError, "k.ply:3: expected 'element <name> <count>'"));
  EXPECT_TRUE(IsError(ReadPly("ply\nformat ascii 1.0\nend_header extra\n", "k.ply"),
                      ErrorCode::kParseError, "k.ply:3: unexpected text after end_header"));
}

TEST(PlyReaderTest, RejectsPropertyBeforeElement) {
  EXPECT_TRUE(IsError(ReadPly(AsciiWithHeader("property float x\n", ""), "p.ply"),
                      ErrorCode::kParseError, "p.ply:3: property before any element"));
}

TEST(PlyReaderTest, RejectsBadElementCounts) {
  for (const char* count : {"-1", "x", "1.5", "99999999999999999999999"}) {
    EXPECT_TRUE(IsError(
        ReadPly(AsciiWithHeader(std::string("element vertex ") + count + "\n", ""), "c.ply"),
        ErrorCode::kParseError,
        "c.ply:3: element count '" + std::string(count) + "' is not a non-negative integer"))
        << count;
  }
}

TEST(PlyReaderTest, RejectsDuplicateElementsAndProperties) {
  EXPECT_TRUE(IsError(ReadPly(AsciiWithHeader(std::string(kVertexXyz) + kVertexXyz, ""), "d.ply"),
                      ErrorCode::kParseError, "d.ply:7: duplicate element 'vertex'"));
  EXPECT_TRUE(IsError(
      ReadPly(AsciiWithHeader("element vertex 1\nproperty float x\nproperty double x\n", ""),
              "d.ply"),
      ErrorCode::kParseError, "d.ply:5: duplicate property 'x' in element 'vertex'"));
}

TEST(PlyReaderTest, RejectsNonIntegerListTypes) {
  EXPECT_TRUE(IsError(
      ReadPly(AsciiWithHeader(std::string(kVertexXyz) +
                                  "element face 1\nproperty list float int vertex_indices\n",
                              ""),
              "l.ply"),
      ErrorCode::kParseError, "l.ply:8: list count type must be an integer type, not 'float'"));
  EXPECT_TRUE(IsError(
      ReadPly(AsciiWithHeader(std::string(kVertexXyz) +
                                  "element face 1\nproperty list uchar float vertex_indices\n",
                              ""),
              "l.ply"),
      ErrorCode::kParseError,
      "l.ply:7: face property 'vertex_indices' must have an integer index type, not 'float'"));
}

TEST(PlyReaderTest, RejectsMissingGeometryElements) {
  EXPECT_TRUE(IsError(ReadPly(AsciiWithHeader(kVertexXyz, "0 0 0\n1 0 0\n0 1 0\n"), "g.ply"),
                      ErrorCode::kParseError, "g.ply: no triangles (no 'face' element)"));
  EXPECT_TRUE(IsError(ReadPly(AsciiWithHeader(kFaceList, "3 0 1 2\n"), "g.ply"),
                      ErrorCode::kParseError, "g.ply:3: 'face' element but no 'vertex' element"));
  EXPECT_TRUE(IsError(
      ReadPly(AsciiWithHeader(std::string(kVertexXyz) +
                                  "element face 0\nproperty list uchar int vertex_indices\n",
                              "0 0 0\n1 0 0\n0 1 0\n"),
              "g.ply"),
      ErrorCode::kParseError, "g.ply: no triangles (0 faces)"));
}

TEST(PlyReaderTest, RejectsVertexElementWithoutXyzScalars) {
  EXPECT_TRUE(IsError(
      ReadPly(AsciiWithHeader(
                  std::string("element vertex 3\nproperty float x\nproperty float y\n") + kFaceList,
                  ""),
              "v.ply"),
      ErrorCode::kParseError, "v.ply:3: element 'vertex' has no property 'z'"));
  EXPECT_TRUE(
      IsError(ReadPly(AsciiWithHeader(std::string("element vertex 3\nproperty list uchar float "
                                                  "x\nproperty float y\nproperty float z\n") +
                                          kFaceList,
                                      ""),
                      "v.ply"),
              ErrorCode::kParseError, "v.ply:3: vertex property 'x' must be a scalar, not a list"));
}

TEST(PlyReaderTest, RejectsFaceElementWithoutIndexList) {
  EXPECT_TRUE(IsError(
      ReadPly(
          AsciiWithHeader(
              std::string(kVertexXyz) + "element face 1\nproperty list uchar int indices\n", ""),
          "f.ply"),
      ErrorCode::kParseError,
      "f.ply:7: element 'face' has no list property 'vertex_indices' or 'vertex_index'"));
  EXPECT_TRUE(IsError(
      ReadPly(AsciiWithHeader(
                  std::string(kVertexXyz) + "element face 1\nproperty int vertex_indices\n", ""),
              "f.ply"),
      ErrorCode::kParseError, "f.ply:7: face property 'vertex_indices' must be a list"));
  EXPECT_TRUE(IsError(ReadPly(AsciiWithHeader(std::string(kVertexXyz) + kFaceList +
                                                  "property list uchar int vertex_index\n",
                                              ""),
                              "f.ply"),
                      ErrorCode::kParseError,
                      "f.ply:7: element 'face' has both 'vertex_indices' and 'vertex_index'"));
}

TEST(PlyReaderTest, RejectsElementWithoutProperties) {
  EXPECT_TRUE(IsError(
      ReadPly(AsciiWithHeader(std::string("element empty 5\n") + kVertexXyz + kFaceList, ""),
              "e.ply"),
      ErrorCode::kParseError, "e.ply:3: element 'empty' has no properties"));
}

// Hostile sizes: counts are checked against the file size before anything is allocated.

TEST(PlyReaderTest, RejectsHugeVertexCountBeforeAllocating) {
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    const std::string bytes =
        std::string("ply\nformat ") + format +
        " 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\n"
        "property float z\n" +
        kFaceList + "end_header\n" + "0 0 0\n";
    const auto start = std::chrono::steady_clock::now();
    EXPECT_TRUE(IsError(ReadPly(bytes, "huge.ply"), ErrorCode::kParseError,
                        "huge.ply: byte " + std::to_string(bytes.size() - 6) +
                            ": truncated: header says 4000000000 'vertex' elements"))
        << format;
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(1)) << format;
  }
}

TEST(PlyReaderTest, RejectsHugeFaceAndOtherElementCounts) {
  EXPECT_TRUE(IsError(
      ReadPly(AsciiWithHeader(std::string(kVertexXyz) + "element face 18446744073709551615\n"
                                                        "property list uchar int vertex_indices\n",
                              kTriangleBody),
              "h.ply"),
      ErrorCode::kParseError, "header says 18446744073709551615 'face' elements"));
  EXPECT_TRUE(IsError(ReadPly("ply\nformat binary_little_endian 1.0\nelement junk 3000000000\n"
                              "property double a\n" +
                                  std::string(kVertexXyz) + kFaceList + "end_header\n",
                              "h.ply"),
                      ErrorCode::kParseError,
                      "header says 3000000000 'junk' elements (at least 8 bytes each)"));
}

TEST(PlyReaderTest, RejectsHugeListCountInBinary) {
  Bytes bytes;
  bytes.Text(std::string("ply\nformat binary_little_endian 1.0\n") +
             "element vertex 3\nproperty uchar x\nproperty uchar y\nproperty uchar z\n"
             "element face 1\nproperty list uint uint vertex_indices\nend_header\n");
  const size_t body = bytes.size();
  for (int i = 0; i < 9; ++i) bytes.Put<uint8_t>(0);
  bytes.Put<uint32_t>(4000000000u).Put<uint32_t>(0).Put<uint32_t>(1).Put<uint32_t>(2);
  EXPECT_TRUE(IsError(ReadPly(bytes.str(), "l.ply"), ErrorCode::kParseError,
                      "l.ply: byte " + std::to_string(body + 9) +
                          ": face 0: truncated: list of 4000000000 values runs past the end"));
}

TEST(PlyReaderTest, RejectsHugeListCountInAscii) {
  EXPECT_TRUE(
      IsError(ReadPly(AsciiWithHeader(std::string(kVertexXyz) +
                                          "element face 1\nproperty list uint int vertex_indices\n",
                                      "0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n"),
                      "l.ply"),
              ErrorCode::kParseError,
              "l.ply:13: face 0: list of 4000000000 values does not fit on the line"));
}

// Body errors: binary ones name the byte offset, ascii ones the line.

std::string BinaryTriangleHeader() {
  return "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
         "property float y\nproperty float z\nelement face 1\n"
         "property list uchar int vertex_indices\nend_header\n";
}

TEST(PlyReaderTest, RejectsTruncatedBinaryBody) {
  Bytes bytes;
  bytes.Text(BinaryTriangleHeader());
  for (int i = 0; i < 9; ++i) bytes.Put<float>(static_cast<float>(i));
  bytes.Put<uint8_t>(4).Put<int32_t>(0).Put<int32_t>(1).Put<int32_t>(2);  // announces 4, has 3
  const Result<Mesh> mesh = ReadPly(bytes.str(), "t.ply");
  EXPECT_TRUE(IsError(mesh, ErrorCode::kParseError,
                      "t.ply: byte " + std::to_string(bytes.size() - 13) +
                          ": face 0: truncated: list of 4 values runs past the end"));
  // Cut inside the vertices: the size check catches it before the body is read.
  const std::string cut = bytes.str().substr(0, BinaryTriangleHeader().size() + 20);
  EXPECT_TRUE(IsError(ReadPly(cut, "t.ply"), ErrorCode::kParseError, "truncated"));
}

TEST(PlyReaderTest, RejectsTrailingBytesInBinary) {
  Bytes bytes;
  bytes.Text(BinaryTriangleHeader());
  for (int i = 0; i < 9; ++i) bytes.Put<float>(static_cast<float>(i));
  bytes.Put<uint8_t>(3).Put<int32_t>(0).Put<int32_t>(1).Put<int32_t>(2);
  const size_t end = bytes.size();
  bytes.Put<int32_t>(7);
  EXPECT_TRUE(IsError(ReadPly(bytes.str(), "x.ply"), ErrorCode::kParseError,
                      "x.ply: byte " + std::to_string(end) +
                          ": 4 bytes of unexpected data after the last element"));
}

TEST(PlyReaderTest, RejectsBinaryIndexOutOfRangeWithByteOffset) {
  Bytes bytes;
  bytes.Text(BinaryTriangleHeader());
  const size_t body = bytes.size();
  for (int i = 0; i < 9; ++i) bytes.Put<float>(static_cast<float>(i));
  bytes.Put<uint8_t>(3).Put<int32_t>(0).Put<int32_t>(3).Put<int32_t>(2);
  EXPECT_TRUE(IsError(ReadPly(bytes.str(), "r.ply"), ErrorCode::kParseError,
                      "r.ply: byte " + std::to_string(body + 36 + 1 + 4) +
                          ": face 0: vertex index 3 out of range (3 vertices)"));
}

TEST(PlyReaderTest, RejectsBinaryNegativeIndexAndCount) {
  Bytes bytes;
  bytes.Text(BinaryTriangleHeader());
  for (int i = 0; i < 9; ++i) bytes.Put<float>(static_cast<float>(i));
  bytes.Put<uint8_t>(3).Put<int32_t>(0).Put<int32_t>(-1).Put<int32_t>(2);
  EXPECT_TRUE(IsError(ReadPly(bytes.str(), "n.ply"), ErrorCode::kParseError,
                      "face 0: vertex index -1 out of range (3 vertices)"));
  Bytes count;
  count.Text(
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list char int vertex_indices\nend_header\n");
  for (int i = 0; i < 9; ++i) count.Put<float>(static_cast<float>(i));
  count.Put<int8_t>(-3).Put<int32_t>(0).Put<int32_t>(1).Put<int32_t>(2);
  EXPECT_TRUE(IsError(ReadPly(count.str(), "n.ply"), ErrorCode::kParseError,
                      "face 0: list 'vertex_indices' has negative count -3"));
}

TEST(PlyReaderTest, RejectsBinaryNonFiniteCoordinates) {
  for (const float bad :
       {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    Bytes bytes;
    bytes.Text(BinaryTriangleHeader());
    const size_t body = bytes.size();
    for (int i = 0; i < 9; ++i) bytes.Put<float>(i == 4 ? bad : 0.0f);
    bytes.Put<uint8_t>(3).Put<int32_t>(0).Put<int32_t>(1).Put<int32_t>(2);
    EXPECT_TRUE(IsError(
        ReadPly(bytes.str(), "nan.ply"), ErrorCode::kParseError,
        "nan.ply: byte " + std::to_string(body + 16) + ": vertex 1: coordinate 'y' is not finite"));
  }
}

TEST(PlyReaderTest, RejectsBinaryFaceWithTooFewIndices) {
  Bytes bytes;
  bytes.Text(BinaryTriangleHeader());
  for (int i = 0; i < 9; ++i) bytes.Put<float>(0.0f);
  bytes.Put<uint8_t>(2).Put<int32_t>(0).Put<int32_t>(1).Put<int32_t>(2);  // pads the size check
  EXPECT_TRUE(IsError(ReadPly(bytes.str(), "f.ply"), ErrorCode::kParseError,
                      "face 0: face has 2 vertex indices (need at least 3)"));
}

TEST(PlyReaderTest, RejectsAsciiLinesWithMissingOrExtraValues) {
  EXPECT_TRUE(IsError(
      ReadPly(AsciiWithHeader(std::string(kVertexXyz) + kFaceList, "0 0 0\n1 0\n0 1 0\n3 0 1 2\n"),
              "a.ply"),
      ErrorCode::kParseError, "a.ply:11: vertex 1: line ends after 2 values"));
  EXPECT_TRUE(IsError(
      ReadPly(
          AsciiWithHeader(std::string(kVertexXyz) + kFaceList, "0 0 0\n1 0 0 5\n0 1 0\n3 0 1 2\n"),
          "a.ply"),
      ErrorCode::kParseError, "a.ply:11: vertex 1: unexpected value '5' after 3 values"));
  EXPECT_TRUE(IsError(
      ReadPly(
          AsciiWithHeader(std::string(kVertexXyz) + kFaceList, "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 0\n"),
          "a.ply"),
      ErrorCode::kParseError, "a.ply:13: face 0: unexpected value '0' after 4 values"));
}

TEST(PlyReaderTest, RejectsAsciiBadNumbers) {
  EXPECT_TRUE(IsError(ReadPly(AsciiWithHeader(std::string(kVertexXyz) + kFaceList,
                                              "0 0 0\n1 abc 0\n0 1 0\n3 0 1 2\n"),
                              "a.ply"),
                      ErrorCode::kParseError, "a.ply:11: vertex 1: value 'abc' is not a number"));
  EXPECT_TRUE(IsError(
      ReadPly(
          AsciiWithHeader(std::string(kVertexXyz) + kFaceList, "0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n"),
          "a.ply"),
      ErrorCode::kParseError, "a.ply:13: face 0: value '1.5' is not an integer (type int)"));
  EXPECT_TRUE(IsError(
      ReadPly(
          AsciiWithHeader(std::string(kVertexXyz) + kFaceList, "0 0 0\n1 0 0\n0 1 0\n300 0 1 2\n"),
          "a.ply"),
      ErrorCode::kParseError, "a.ply:13: face 0: value '300' is out of range for type uchar"));
  EXPECT_TRUE(IsError(ReadPly(AsciiWithHeader(std::string(kVertexXyz) + kFaceList,
                                              "0 0 0\n1 0 1e999\n0 1 0\n3 0 1 2\n"),
                              "a.ply"),
                      ErrorCode::kParseError,
                      "a.ply:11: vertex 1: value '1e999' is out of double range"));
}

TEST(PlyReaderTest, RejectsAsciiNonFiniteCoordinates) {
  EXPECT_TRUE(IsError(
      ReadPly(
          AsciiWithHeader(std::string(kVertexXyz) + kFaceList, "0 0 0\n1 0 0\n0 1 nan\n3 0 1 2\n"),
          "a.ply"),
      ErrorCode::kParseError, "a.ply:12: vertex 2: coordinate 'z' is not finite (nan)"));
  EXPECT_TRUE(IsError(
      ReadPly(
          AsciiWithHeader(std::string(kVertexXyz) + kFaceList, "-inf 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
          "a.ply"),
      ErrorCode::kParseError, "a.ply:10: vertex 0: coordinate 'x' is not finite (-inf)"));
}

TEST(PlyReaderTest, RejectsAsciiIndexErrors) {
  EXPECT_TRUE(IsError(
      ReadPly(
          AsciiWithHeader(std::string(kVertexXyz) + kFaceList, "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
          "a.ply"),
      ErrorCode::kParseError, "a.ply:13: face 0: vertex index 3 out of range (3 vertices)"));
  EXPECT_TRUE(IsError(ReadPly(AsciiWithHeader(std::string(kVertexXyz) + kFaceList,
                                              "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n"),
                              "a.ply"),
                      ErrorCode::kParseError, "vertex index -1 out of range"));
  EXPECT_TRUE(IsError(
      ReadPly(AsciiWithHeader(std::string(kVertexXyz) + kFaceList, "0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
              "a.ply"),
      ErrorCode::kParseError, "a.ply:13: face 0: face has 2 vertex indices (need at least 3)"));
  EXPECT_TRUE(IsError(
      ReadPly(AsciiWithHeader(std::string(kVertexXyz) +
                                  "element face 1\nproperty list char int vertex_indices\n",
                              "0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n"),
              "a.ply"),
      ErrorCode::kParseError, "a.ply:13: face 0: list 'vertex_indices' has negative count -3"));
}

TEST(PlyReaderTest, RejectsAsciiTruncatedAndTrailingData) {
  EXPECT_TRUE(IsError(
      ReadPly(AsciiWithHeader(std::string(kVertexXyz) +
                                  "element face 2\nproperty list uchar int vertex_indices\n",
                              "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
              "a.ply"),
      ErrorCode::kParseError, "truncated"));
  EXPECT_TRUE(IsError(ReadPly(AsciiWithHeader(std::string(kVertexXyz) + kFaceList,
                                              std::string(kTriangleBody) + "\n3 0 1 2\n"),
                              "a.ply"),
                      ErrorCode::kParseError, "a.ply:15: unexpected data after the last element"));
}

TEST(PlyReaderTest, ReportsMissingFileAsIoError) {
  TempDir dir;
  EXPECT_TRUE(IsError(ReadPly(dir / "nope.ply"), ErrorCode::kIoError, "nope.ply: cannot open"));
}

}  // namespace
}  // namespace far
