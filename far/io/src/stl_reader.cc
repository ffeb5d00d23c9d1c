// STL reader (binary and ascii).
//
// Hand-written on purpose: general loaders (assimp and friends) guess the variant loosely,
// accept a binary file whose triangle count disagrees with its size (reading garbage or
// dropping the tail) and skip malformed ascii facets. This reader decides the variant by one
// documented rule, checks the count against the size before allocating, and rejects the file
// with the line or byte offset of the first problem.
//
// Variant rule: a file of exactly 84 + 50 n bytes, n being the little-endian uint32 at byte 80,
// is binary, even when it starts with "solid" (the known STL ambiguity: many binary exporters
// put "solid" in the 80-byte header; an ascii file of exactly that size is misread as binary).
// Otherwise a text file starting with "solid" is ascii; anything else is a binary file of the
// wrong size. STL shares no vertices: facet t gives vertices 3t, 3t+1, 3t+2, never welded.

#include <cmath>
#include <string>
#include <string_view>

#include "io_util.h"

#include "far/io/mesh_io.h"

namespace far {
namespace {

using internal::NumberStatus;
using internal::Quote;

constexpr size_t kHeaderSize = 84;  // 80-byte comment + uint32 triangle count
constexpr size_t kFacetSize = 50;   // normal, 3 vertices (12 float32), uint16 attribute

bool EqualsIgnoreCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    const char ca = (a[i] >= 'A' && a[i] <= 'Z') ? static_cast<char>(a[i] - 'A' + 'a') : a[i];
    const char cb = (b[i] >= 'A' && b[i] <= 'Z') ? static_cast<char>(b[i] - 'A' + 'a') : b[i];
    if (ca != cb) return false;
  }
  return true;
}

// True when `bytes` has no control bytes other than whitespace (binary float data always does).
bool LooksLikeText(std::string_view bytes) {
  for (const char c : bytes) {
    const unsigned char u = static_cast<unsigned char>(c);
    if ((u < 0x20 && !internal::IsSpace(c)) || u == 0x7f) return false;
  }
  return true;
}

Result<Mesh> ParseBinary(std::string_view bytes, std::string_view name, uint64_t count) {
  if (count == 0) {
    return MakeError(ErrorCode::kParseError,
                     std::string(name) + ": no triangles (binary STL header says 0)");
  }
  if (3 * count > kMaxMeshElements) {
    return MakeError(ErrorCode::kLimitExceeded, std::string(name) +
                                                    ": byte 80: " + std::to_string(count) +
                                                    " triangles need more than 2^31-1 vertices");
  }
  Mesh mesh;
  mesh.p_MV.reserve(3 * count);
  mesh.triangles.reserve(count);
  for (uint64_t t = 0; t < count; ++t) {
    const size_t facet = kHeaderSize + t * kFacetSize;
    // Skip the normal (12 bytes); read three vertices of three float32 each.
    for (size_t k = 0; k < 3; ++k) {
      Eigen::Vector3d p_MV;
      for (size_t axis = 0; axis < 3; ++axis) {
        const size_t offset = facet + 12 + 12 * k + 4 * axis;
        const float value =
            internal::LoadScalar<float>(bytes.data() + offset, internal::ByteOrder::kLittle);
        if (!std::isfinite(value)) {
          return MakeError(ErrorCode::kParseError,
                           std::string(name) + ": byte " + std::to_string(offset) + ": triangle " +
                               std::to_string(t) + " vertex " + std::to_string(k) +
                               ": coordinate " + "xyz"[axis] + " is not finite (" +
                               internal::FormatDouble(value) + ")");
        }
        p_MV[axis] = value;
      }
      mesh.p_MV.push_back(p_MV);
    }
    const uint32_t first = static_cast<uint32_t>(3 * t);
    mesh.triangles.push_back({first, first + 1, first + 2});
  }
  return mesh;
}

// Whitespace-separated tokens of an ascii STL file with their line numbers.
class AsciiParser {
 public:
  AsciiParser(std::string_view bytes, std::string_view name) : bytes_(bytes), name_(name) {}

  Result<Mesh> Parse() {
    if (bytes_.starts_with("\xEF\xBB\xBF")) pos_ = 3;
    // solid [name] ... endsolid [name], possibly several solids one after another.
    if (Result<void> status = Expect("solid"); !status.ok()) return status.error();
    SkipRestOfLine();
    while (true) {
      const std::string_view token = Next();
      if (token.empty()) return Fail("truncated: file ends before 'endsolid'");
      if (EqualsIgnoreCase(token, "endsolid")) {
        SkipRestOfLine();
        const std::string_view after = Next();
        if (after.empty()) break;
        if (!EqualsIgnoreCase(after, "solid")) {
          return Fail("unexpected " + Quote(after) + " after 'endsolid'");
        }
        SkipRestOfLine();
        continue;
      }
      if (!EqualsIgnoreCase(token, "facet")) {
        return Fail("expected 'facet' or 'endsolid', got " + Quote(token));
      }
      if (Result<void> status = ParseFacet(); !status.ok()) return status.error();
    }
    if (mesh_.triangles.empty()) {
      return MakeError(ErrorCode::kParseError, std::string(name_) + ": no triangles (no facets)");
    }
    return std::move(mesh_);
  }

 private:
  Error Fail(const std::string& what) const {
    return MakeError(ErrorCode::kParseError,
                     std::string(name_) + ":" + std::to_string(line_number_) + ": " + what);
  }

  // Returns the next token (empty at the end of the file), counting line breaks on the way.
  std::string_view Next() {
    while (pos_ < bytes_.size() && internal::IsSpace(bytes_[pos_])) {
      if (bytes_[pos_] == '\n') ++line_number_;
      ++pos_;
    }
    const size_t begin = pos_;
    while (pos_ < bytes_.size() && !internal::IsSpace(bytes_[pos_])) ++pos_;
    return bytes_.substr(begin, pos_ - begin);
  }

  void SkipRestOfLine() {
    while (pos_ < bytes_.size() && bytes_[pos_] != '\n') ++pos_;
  }

  Result<void> Expect(std::string_view keyword) {
    const std::string_view token = Next();
    if (token.empty()) return Fail("expected '" + std::string(keyword) + "', file ends");
    if (!EqualsIgnoreCase(token, keyword)) {
      return Fail("expected '" + std::string(keyword) + "', got " + Quote(token));
    }
    return {};
  }

  // Reads three numbers; `finite` demands finite values (vertices; normals may be "nan").
  Result<Eigen::Vector3d> Numbers(const char* what, bool finite) {
    Eigen::Vector3d values;
    for (int axis = 0; axis < 3; ++axis) {
      const std::string_view token = Next();
      if (token.empty()) return Fail(std::string(what) + ": file ends inside the coordinates");
      double value = 0;
      const NumberStatus status = internal::ParseDouble(token, &value);
      if (status == NumberStatus::kOutOfRange) {
        return Fail(std::string(what) + ": " + Quote(token) + " is out of double range");
      }
      if (status != NumberStatus::kOk) {
        return Fail(std::string(what) + ": " + Quote(token) + " is not a number");
      }
      if (finite && !std::isfinite(value)) {
        return Fail(std::string(what) + ": coordinate " + Quote(token) + " is not finite");
      }
      values[axis] = value;
    }
    return values;
  }

  // facet normal nx ny nz / outer loop / vertex x y z (x3) / endloop / endfacet
  Result<void> ParseFacet() {
    if (Result<void> status = Expect("normal"); !status.ok()) return status;
    if (Result<Eigen::Vector3d> normal = Numbers("normal", false); !normal.ok()) {
      return normal.error();
    }
    if (Result<void> status = Expect("outer"); !status.ok()) return status;
    if (Result<void> status = Expect("loop"); !status.ok()) return status;
    if (3 * (mesh_.triangles.size() + 1) > kMaxMeshElements) {
      Error error = Fail("more than 2^31-1 vertices");
      error.code = ErrorCode::kLimitExceeded;
      return error;
    }
    const uint32_t first = static_cast<uint32_t>(mesh_.p_MV.size());
    for (int k = 0; k < 3; ++k) {
      if (Result<void> status = Expect("vertex"); !status.ok()) return status;
      Result<Eigen::Vector3d> p_MV = Numbers("vertex", true);
      if (!p_MV.ok()) return p_MV.error();
      mesh_.p_MV.push_back(*p_MV);
    }
    if (Result<void> status = Expect("endloop"); !status.ok()) return status;
    if (Result<void> status = Expect("endfacet"); !status.ok()) return status;
    mesh_.triangles.push_back({first, first + 1, first + 2});
    return {};
  }

  std::string_view bytes_;
  std::string_view name_;
  size_t pos_ = 0;
  size_t line_number_ = 1;
  Mesh mesh_;
};

}  // namespace

Result<Mesh> ReadStl(std::string_view bytes, std::string_view name_for_errors) {
  const std::string name(name_for_errors);
  // Binary when the size matches the header's count exactly.
  uint64_t count = 0;
  if (bytes.size() >= kHeaderSize) {
    count = internal::LoadScalar<uint32_t>(bytes.data() + 80, internal::ByteOrder::kLittle);
    if (bytes.size() == kHeaderSize + kFacetSize * count) {
      return ParseBinary(bytes, name_for_errors, count);
    }
  }
  // Otherwise ascii when it is text starting with "solid".
  std::string_view text = bytes;
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);
  if (text.size() >= 5 && EqualsIgnoreCase(text.substr(0, 5), "solid") && LooksLikeText(bytes)) {
    return AsciiParser(bytes, name_for_errors).Parse();
  }
  // Otherwise a binary file whose size disagrees with its header.
  if (bytes.size() < kHeaderSize) {
    return MakeError(ErrorCode::kParseError,
                     name + ": byte 0: not an STL file: " + std::to_string(bytes.size()) +
                         " bytes is too small for binary STL (84-byte header) and it is not "
                         "ascii STL text starting with 'solid'");
  }
  const uint64_t room = (bytes.size() - kHeaderSize) / kFacetSize;
  if (room < count) {
    return MakeError(ErrorCode::kParseError,
                     name + ": byte 84: truncated: header says " + std::to_string(count) +
                         " triangles, file has room for " + std::to_string(room));
  }
  const uint64_t end = kHeaderSize + kFacetSize * count;
  return MakeError(ErrorCode::kParseError,
                   name + ": byte " + std::to_string(end) + ": header says " +
                       std::to_string(count) + " triangles, but " +
                       std::to_string(bytes.size() - end) + " more bytes follow them");
}

Result<Mesh> ReadStl(const std::filesystem::path& path) {
  Result<std::string> bytes = internal::ReadFileBytes(path);
  if (!bytes.ok()) return bytes.error();
  return ReadStl(*bytes, path.string());
}

}  // namespace far
