// Wavefront OBJ reader.
//
// Hand-written on purpose: tinyobjloader and assimp fill missing coordinates with defaults,
// clamp or skip bad indices and silently skip lines they do not understand, so they cannot give
// this project's guarantee that a file is either read whole or rejected with an error naming
// the line and what is wrong. This reader only handles the part of OBJ that carries triangle
// geometry (v and f) and is strict about it; see ReadObj in far/mesh_io.h for what it accepts.

#include <array>
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "io_util.h"

#include "far/io/mesh_io.h"

namespace far {
namespace {

using internal::NextToken;
using internal::NumberStatus;
using internal::Quote;

// Statements that carry no triangle geometry: accepted and ignored (vt, vn and vp are counted
// so that face references to them can be range-checked).
constexpr std::array<std::string_view, 18> kIgnoredStatements = {
    "l",      "p",     "g",        "o",        "s",   "mg",         "usemtl",    "mtllib", "usemap",
    "maplib", "bevel", "c_interp", "d_interp", "lod", "shadow_obj", "trace_obj", "ctech",  "stech"};

// Free-form curves and surfaces: real geometry this reader cannot triangulate, so an error.
constexpr std::array<std::string_view, 14> kFreeFormStatements = {
    "cstype", "deg",  "bmat", "step", "curv", "curv2", "surf",
    "parm",   "trim", "hole", "scrv", "sp",   "end",   "con"};

template <size_t N>
bool Contains(const std::array<std::string_view, N>& list, std::string_view word) {
  for (std::string_view entry : list) {
    if (entry == word) return true;
  }
  return false;
}

class ObjParser {
 public:
  ObjParser(std::string_view bytes, std::string_view name) : bytes_(bytes), name_(name) {}

  Result<Mesh> Parse() {
    size_t pos = 0;
    // Skip a UTF-8 byte order mark some Windows tools write.
    if (bytes_.starts_with("\xEF\xBB\xBF")) pos = 3;
    while (pos < bytes_.size()) {
      ++line_number_;
      std::string_view line = internal::NextLine(bytes_, &pos);
      // Drop a trailing comment, then dispatch on the statement keyword.
      if (const size_t hash = line.find('#'); hash != std::string_view::npos) {
        line = line.substr(0, hash);
      }
      size_t cursor = 0;
      const std::string_view keyword = NextToken(line, &cursor);
      if (keyword.empty()) continue;
      const std::string_view rest = line.substr(cursor);
      if (const size_t last = line.find_last_not_of(" \t\r\v\f");
          last != std::string_view::npos && line[last] == '\\') {
        return Fail("line continuation '\\' is not supported");
      }
      Result<void> status;
      if (keyword == "v") {
        status = ParseVertex(rest);
      } else if (keyword == "f") {
        status = ParseFace(rest);
      } else if (keyword == "vt") {
        ++num_texcoords_;
      } else if (keyword == "vn") {
        ++num_normals_;
      } else if (keyword == "vp" || Contains(kIgnoredStatements, keyword)) {
        // No triangle geometry here.
      } else if (Contains(kFreeFormStatements, keyword)) {
        return Fail("free-form geometry statement " + Quote(keyword) + " is not supported");
      } else {
        return Fail("unknown statement " + Quote(keyword));
      }
      if (!status.ok()) return status.error();
    }
    if (mesh_.triangles.empty()) {
      return MakeError(ErrorCode::kParseError, std::string(name_) + ": no triangles (" +
                                                   std::to_string(mesh_.p_MV.size()) +
                                                   " vertices, no faces)");
    }
    return std::move(mesh_);
  }

 private:
  Error Fail(const std::string& what, ErrorCode code = ErrorCode::kParseError) const {
    return MakeError(code, std::string(name_) + ":" + std::to_string(line_number_) + ": " + what);
  }

  // v x y z [w], or v x y z r g b (vertex colors, a common extension).
  Result<void> ParseVertex(std::string_view rest) {
    std::array<double, 6> values{};
    size_t count = 0;
    size_t cursor = 0;
    for (std::string_view token = NextToken(rest, &cursor); !token.empty();
         token = NextToken(rest, &cursor)) {
      if (count == values.size()) {
        return Fail("vertex has too many values (expected x y z [w] or x y z r g b)");
      }
      double value = 0;
      switch (internal::ParseDouble(token, &value)) {
        case NumberStatus::kGarbage:
          return Fail("vertex value " + Quote(token) + " is not a number");
        case NumberStatus::kOutOfRange:
          return Fail("vertex value " + Quote(token) + " is out of double range");
        case NumberStatus::kOk:
          break;
      }
      if (!std::isfinite(value)) return Fail("vertex value " + Quote(token) + " is not finite");
      values[count++] = value;
    }
    if (count < 3) {
      return Fail("vertex has " + std::to_string(count) + " coordinates (expected x y z [w])");
    }
    if (count == 5) return Fail("vertex has 5 values (expected x y z [w] or x y z r g b)");
    if (mesh_.p_MV.size() >= kMaxMeshElements) {
      return Fail("more than 2^31-1 vertices", ErrorCode::kLimitExceeded);
    }
    mesh_.p_MV.emplace_back(values[0], values[1], values[2]);
    return {};
  }

  // Turns a 1-based or negative (relative) reference into a 0-based index below `count`.
  Result<uint32_t> ResolveIndex(std::string_view token, const char* what, uint64_t count,
                                const char* count_name) const {
    int64_t raw = 0;
    if (internal::ParseInt64(token, &raw) != NumberStatus::kOk) {
      return Fail(std::string(what) + " index " + Quote(token) + " is not an integer");
    }
    if (raw == 0) return Fail(std::string(what) + " index 0 is invalid (OBJ indices start at 1)");
    const uint64_t magnitude =
        raw > 0 ? static_cast<uint64_t>(raw) : 0 - static_cast<uint64_t>(raw);
    if (magnitude > count) {
      return Fail(std::string(what) + " index " + std::to_string(raw) + " out of range (" +
                  std::to_string(count) + " " + count_name + ")");
    }
    return static_cast<uint32_t>(raw > 0 ? magnitude - 1 : count - magnitude);
  }

  // f v1 v2 v3 ... with references i, i/t, i//n or i/t/n; fan-triangulated in file order.
  Result<void> ParseFace(std::string_view rest) {
    corners_.clear();
    size_t cursor = 0;
    for (std::string_view token = NextToken(rest, &cursor); !token.empty();
         token = NextToken(rest, &cursor)) {
      // Split the reference into at most three '/'-separated parts.
      std::array<std::string_view, 3> parts;
      size_t num_parts = 0;
      size_t begin = 0;
      while (true) {
        const size_t slash = token.find('/', begin);
        if (num_parts == parts.size()) return Fail("bad vertex reference " + Quote(token));
        parts[num_parts++] = token.substr(
            begin, slash == std::string_view::npos ? std::string_view::npos : slash - begin);
        if (slash == std::string_view::npos) break;
        begin = slash + 1;
      }
      // Allowed: i, i/t, i//n, i/t/n.
      const bool well_formed = !parts[0].empty() &&
                               (num_parts < 2 || num_parts == 3 || !parts[1].empty()) &&
                               (num_parts < 3 || !parts[2].empty());
      if (!well_formed) {
        return Fail("bad vertex reference " + Quote(token) + " (expected i, i/t, i//n or i/t/n)");
      }
      const Result<uint32_t> vertex = ResolveIndex(parts[0], "face", mesh_.p_MV.size(), "vertices");
      if (!vertex.ok()) return vertex.error();
      if (num_parts >= 2 && !parts[1].empty()) {
        const Result<uint32_t> texcoord =
            ResolveIndex(parts[1], "texture coordinate", num_texcoords_, "texture coordinates");
        if (!texcoord.ok()) return texcoord.error();
      }
      if (num_parts == 3) {
        const Result<uint32_t> normal = ResolveIndex(parts[2], "normal", num_normals_, "normals");
        if (!normal.ok()) return normal.error();
      }
      corners_.push_back(*vertex);
    }
    if (corners_.size() < 3) {
      return Fail("face has " + std::to_string(corners_.size()) + " vertices (need at least 3)");
    }
    if (mesh_.triangles.size() + corners_.size() - 2 > kMaxMeshElements) {
      return Fail("more than 2^31-1 triangles", ErrorCode::kLimitExceeded);
    }
    for (size_t k = 1; k + 1 < corners_.size(); ++k) {
      mesh_.triangles.push_back({corners_[0], corners_[k], corners_[k + 1]});
    }
    return {};
  }

  std::string_view bytes_;
  std::string_view name_;
  size_t line_number_ = 0;
  uint64_t num_texcoords_ = 0;
  uint64_t num_normals_ = 0;
  std::vector<uint32_t> corners_;  // scratch: the current face's vertex indices
  Mesh mesh_;
};

}  // namespace

Result<Mesh> ReadObj(std::string_view bytes, std::string_view name_for_errors) {
  return ObjParser(bytes, name_for_errors).Parse();
}

Result<Mesh> ReadObj(const std::filesystem::path& path) {
  Result<std::string> bytes = internal::ReadFileBytes(path);
  if (!bytes.ok()) return bytes.error();
  return ReadObj(*bytes, path.string());
}

}  // namespace far
