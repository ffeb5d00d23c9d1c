// PLY reader (ascii, binary_little_endian, binary_big_endian).
//
// Hand-written on purpose: general loaders (assimp, tinyply, happly) skip what they do not
// understand, default missing values and trust the header's counts (a header claiming 4e9
// vertices makes them allocate before reading a byte). This reader checks every count against
// the bytes that follow the header before it allocates anything, reads the whole body or
// nothing, and names the line (ascii) or byte offset (binary) of the first problem.

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "io_util.h"

#include "far/io/mesh_io.h"

namespace far {
namespace {

using internal::ByteOrder;
using internal::NextToken;
using internal::NumberStatus;
using internal::Quote;

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

std::optional<PlyType> ParseType(std::string_view word) {
  if (word == "char" || word == "int8") return PlyType::kInt8;
  if (word == "uchar" || word == "uint8") return PlyType::kUint8;
  if (word == "short" || word == "int16") return PlyType::kInt16;
  if (word == "ushort" || word == "uint16") return PlyType::kUint16;
  if (word == "int" || word == "int32") return PlyType::kInt32;
  if (word == "uint" || word == "uint32") return PlyType::kUint32;
  if (word == "float" || word == "float32") return PlyType::kFloat32;
  if (word == "double" || word == "float64") return PlyType::kFloat64;
  return std::nullopt;
}

size_t SizeOf(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 8;
}

bool IsInteger(PlyType type) { return type != PlyType::kFloat32 && type != PlyType::kFloat64; }

// The range of an integer type, for checking ascii values.
std::pair<int64_t, int64_t> RangeOf(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
      return {-128, 127};
    case PlyType::kUint8:
      return {0, 255};
    case PlyType::kInt16:
      return {-32768, 32767};
    case PlyType::kUint16:
      return {0, 65535};
    case PlyType::kInt32:
      return {std::numeric_limits<int32_t>::min(), std::numeric_limits<int32_t>::max()};
    default:
      return {0, std::numeric_limits<uint32_t>::max()};
  }
}

const char* NameOf(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
      return "char";
    case PlyType::kUint8:
      return "uchar";
    case PlyType::kInt16:
      return "short";
    case PlyType::kUint16:
      return "ushort";
    case PlyType::kInt32:
      return "int";
    case PlyType::kUint32:
      return "uint";
    case PlyType::kFloat32:
      return "float";
    case PlyType::kFloat64:
      return "double";
  }
  return "?";
}

struct Property {
  std::string name;
  bool is_list = false;
  PlyType type = PlyType::kFloat32;     // the scalar type, or the list's count type
  PlyType item_type = PlyType::kInt32;  // lists only
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
  size_t header_line = 0;
};

enum class PlyFormat { kAscii, kBinaryLittle, kBinaryBig };

struct Header {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<Element> elements;
  size_t body_offset = 0;      // byte offset of the first byte after "end_header\n"
  size_t body_first_line = 0;  // line number of the first body line (ascii)
  // Roles found while checking the header: which element and properties hold the geometry.
  int vertex_element = -1;
  int face_element = -1;
  int x = -1, y = -1, z = -1;  // property indices in the vertex element
  int indices = -1;            // property index of the face's index list
};

// Walks the header lines, then checks that the vertex and face elements have what we need.
class HeaderParser {
 public:
  HeaderParser(std::string_view bytes, std::string_view name) : bytes_(bytes), name_(name) {}

  Result<Header> Parse() {
    size_t pos = 0;
    bool seen_format = false;
    while (true) {
      if (pos >= bytes_.size()) {
        return MakeError(ErrorCode::kParseError,
                         std::string(name_) + ": truncated header: no end_header line");
      }
      ++line_number_;
      const std::string_view line = internal::NextLine(bytes_, &pos);
      size_t cursor = 0;
      const std::string_view keyword = NextToken(line, &cursor);
      if (line_number_ == 1) {
        if (line != "ply") return Fail("not a PLY file (the first line must be 'ply')");
        continue;
      }
      if (keyword == "comment" || keyword == "obj_info" || keyword.empty()) continue;
      std::vector<std::string_view> words;
      for (std::string_view word = NextToken(line, &cursor); !word.empty();
           word = NextToken(line, &cursor)) {
        words.push_back(word);
      }
      if (keyword == "format") {
        if (seen_format) return Fail("second format line");
        seen_format = true;
        if (words.size() != 2) {
          return Fail("expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
        }
        if (words[0] == "ascii") {
          header_.format = PlyFormat::kAscii;
        } else if (words[0] == "binary_little_endian") {
          header_.format = PlyFormat::kBinaryLittle;
        } else if (words[0] == "binary_big_endian") {
          header_.format = PlyFormat::kBinaryBig;
        } else {
          return Fail("unknown format " + Quote(words[0]));
        }
        if (words[1] != "1.0") return Fail("unsupported PLY version " + Quote(words[1]));
      } else if (keyword == "element") {
        if (!seen_format) return Fail("element before the format line");
        if (Result<void> status = ParseElement(words); !status.ok()) return status.error();
      } else if (keyword == "property") {
        if (header_.elements.empty()) return Fail("property before any element");
        if (Result<void> status = ParseProperty(words); !status.ok()) return status.error();
      } else if (keyword == "end_header") {
        if (!words.empty()) return Fail("unexpected text after end_header");
        if (!seen_format) return Fail("end_header before the format line");
        break;
      } else {
        return Fail("unknown header keyword " + Quote(keyword));
      }
    }
    header_.body_offset = pos;
    header_.body_first_line = line_number_ + 1;
    if (Result<void> status = FindGeometry(); !status.ok()) return status.error();
    return std::move(header_);
  }

 private:
  Error Fail(const std::string& what, size_t line = 0) const {
    return MakeError(
        ErrorCode::kParseError,
        std::string(name_) + ":" + std::to_string(line ? line : line_number_) + ": " + what);
  }

  // element <name> <count>
  Result<void> ParseElement(const std::vector<std::string_view>& words) {
    if (words.size() != 2) return Fail("expected 'element <name> <count>'");
    Element element;
    element.name = std::string(words[0]);
    element.header_line = line_number_;
    if (internal::ParseUint64(words[1], &element.count) != NumberStatus::kOk) {
      return Fail("element count " + Quote(words[1]) + " is not a non-negative integer");
    }
    for (const Element& other : header_.elements) {
      if (other.name == element.name) return Fail("duplicate element " + Quote(element.name));
    }
    header_.elements.push_back(std::move(element));
    return {};
  }

  // property <type> <name> | property list <count type> <item type> <name>
  Result<void> ParseProperty(const std::vector<std::string_view>& words) {
    Property property;
    if (!words.empty() && words[0] == "list") {
      if (words.size() != 4) {
        return Fail("expected 'property list <count type> <item type> <name>'");
      }
      property.is_list = true;
      const std::optional<PlyType> count_type = ParseType(words[1]);
      const std::optional<PlyType> item_type = ParseType(words[2]);
      if (!count_type) return Fail("unknown type " + Quote(words[1]));
      if (!item_type) return Fail("unknown type " + Quote(words[2]));
      if (!IsInteger(*count_type)) {
        return Fail("list count type must be an integer type, not " + Quote(words[1]));
      }
      property.type = *count_type;
      property.item_type = *item_type;
      property.name = std::string(words[3]);
    } else {
      if (words.size() != 2) return Fail("expected 'property <type> <name>'");
      const std::optional<PlyType> type = ParseType(words[0]);
      if (!type) return Fail("unknown type " + Quote(words[0]));
      property.type = *type;
      property.name = std::string(words[1]);
    }
    Element& element = header_.elements.back();
    for (const Property& other : element.properties) {
      if (other.name == property.name) {
        return Fail("duplicate property " + Quote(property.name) + " in element " +
                    Quote(element.name));
      }
    }
    element.properties.push_back(std::move(property));
    return {};
  }

  // Finds element vertex with scalar x, y, z and element face with its index list.
  Result<void> FindGeometry() {
    for (size_t e = 0; e < header_.elements.size(); ++e) {
      const Element& element = header_.elements[e];
      if (element.properties.empty()) {
        return Fail("element " + Quote(element.name) + " has no properties", element.header_line);
      }
      if (element.name == "vertex") header_.vertex_element = static_cast<int>(e);
      if (element.name == "face") header_.face_element = static_cast<int>(e);
    }
    if (header_.face_element < 0) {
      return MakeError(ErrorCode::kParseError,
                       std::string(name_) + ": no triangles (no 'face' element)");
    }
    const Element& face = header_.elements[header_.face_element];
    if (header_.vertex_element < 0) {
      return Fail("'face' element but no 'vertex' element", face.header_line);
    }
    const Element& vertex = header_.elements[header_.vertex_element];
    int* const roles[3] = {&header_.x, &header_.y, &header_.z};
    const char* const axes[3] = {"x", "y", "z"};
    for (size_t p = 0; p < vertex.properties.size(); ++p) {
      for (int axis = 0; axis < 3; ++axis) {
        if (vertex.properties[p].name != axes[axis]) continue;
        if (vertex.properties[p].is_list) {
          return Fail(
              std::string("vertex property '") + axes[axis] + "' must be a scalar, not a list",
              vertex.header_line);
        }
        *roles[axis] = static_cast<int>(p);
      }
    }
    for (int axis = 0; axis < 3; ++axis) {
      if (*roles[axis] < 0) {
        return Fail(std::string("element 'vertex' has no property '") + axes[axis] + "'",
                    vertex.header_line);
      }
    }
    for (size_t p = 0; p < face.properties.size(); ++p) {
      const Property& property = face.properties[p];
      if (property.name != "vertex_indices" && property.name != "vertex_index") continue;
      if (header_.indices >= 0) {
        return Fail("element 'face' has both 'vertex_indices' and 'vertex_index'",
                    face.header_line);
      }
      if (!property.is_list) {
        return Fail("face property " + Quote(property.name) + " must be a list", face.header_line);
      }
      if (!IsInteger(property.item_type)) {
        return Fail(std::string("face property ") + Quote(property.name) +
                        " must have an integer index type, not '" + NameOf(property.item_type) +
                        "'",
                    face.header_line);
      }
      header_.indices = static_cast<int>(p);
    }
    if (header_.indices < 0) {
      return Fail("element 'face' has no list property 'vertex_indices' or 'vertex_index'",
                  face.header_line);
    }
    if (face.count == 0) {
      return MakeError(ErrorCode::kParseError, std::string(name_) + ": no triangles (0 faces)");
    }
    return {};
  }

  std::string_view bytes_;
  std::string_view name_;
  size_t line_number_ = 0;
  Header header_;
};

// Checks that the bytes after the header can hold every element the header announces, using
// the smallest size each element can have: in binary, lists empty except the face's index list
// with 3 indices; in ascii, one character and one separator per scalar and per list count. Runs
// before anything is allocated, so a hostile count fails here instead of in the allocator.
Result<void> CheckCountsAgainstSize(const Header& header, std::string_view bytes,
                                    std::string_view name) {
  const bool ascii = header.format == PlyFormat::kAscii;
  uint64_t available = bytes.size() - header.body_offset;
  // An ascii file may omit the last line break.
  if (ascii) ++available;
  for (size_t e = 0; e < header.elements.size(); ++e) {
    const Element& element = header.elements[e];
    uint64_t min_size = 0;
    for (size_t p = 0; p < element.properties.size(); ++p) {
      const Property& property = element.properties[p];
      const bool index_list =
          static_cast<int>(e) == header.face_element && static_cast<int>(p) == header.indices;
      if (ascii) {
        min_size += 2;
      } else {
        min_size += SizeOf(property.type) + (index_list ? 3 * SizeOf(property.item_type) : 0);
      }
    }
    if (element.count > available / min_size) {
      return MakeError(
          ErrorCode::kParseError,
          std::string(name) + ": byte " + std::to_string(header.body_offset) +
              ": truncated: header says " + std::to_string(element.count) + " '" + element.name +
              "' elements (at least " + std::to_string(min_size) + " bytes each), but only " +
              std::to_string(bytes.size() - header.body_offset) + " bytes follow the header");
    }
    available -= element.count * min_size;
  }
  return {};
}

// Values from the body of a binary file.
class BinarySource {
 public:
  BinarySource(std::string_view bytes, size_t offset, ByteOrder order, std::string_view name)
      : bytes_(bytes), pos_(offset), order_(order), name_(name) {}

  Result<void> BeginElement(const std::string& element, uint64_t index) {
    context_ = element + " " + std::to_string(index);
    value_pos_ = pos_;
    if (pos_ == bytes_.size()) return Fail("truncated: file ends before this element");
    return {};
  }
  Result<void> EndElement() { return {}; }

  // Reads one value of `type` as a double (exact for every integer type).
  Result<double> Scalar(PlyType type) {
    value_pos_ = pos_;
    const size_t size = SizeOf(type);
    if (bytes_.size() - pos_ < size) return Fail("truncated: file ends inside the element");
    const char* p = bytes_.data() + pos_;
    pos_ += size;
    switch (type) {
      case PlyType::kInt8:
        return static_cast<double>(internal::LoadScalar<int8_t>(p, order_));
      case PlyType::kUint8:
        return static_cast<double>(internal::LoadScalar<uint8_t>(p, order_));
      case PlyType::kInt16:
        return static_cast<double>(internal::LoadScalar<int16_t>(p, order_));
      case PlyType::kUint16:
        return static_cast<double>(internal::LoadScalar<uint16_t>(p, order_));
      case PlyType::kInt32:
        return static_cast<double>(internal::LoadScalar<int32_t>(p, order_));
      case PlyType::kUint32:
        return static_cast<double>(internal::LoadScalar<uint32_t>(p, order_));
      case PlyType::kFloat32:
        return static_cast<double>(internal::LoadScalar<float>(p, order_));
      case PlyType::kFloat64:
        return internal::LoadScalar<double>(p, order_);
    }
    return 0.0;
  }

  // Checks that a list of `count` values of `type` fits in the rest of the file.
  Result<void> CheckListFits(PlyType type, uint64_t count) {
    if (count > (bytes_.size() - pos_) / SizeOf(type)) {
      return Fail("truncated: list of " + std::to_string(count) + " values runs past the end");
    }
    return {};
  }

  // Skips `count` values of `type` (a list we do not need).
  Result<void> SkipList(PlyType type, uint64_t count) {
    if (Result<void> status = CheckListFits(type, count); !status.ok()) return status;
    pos_ += count * SizeOf(type);
    return {};
  }

  Result<void> Finish() {
    if (pos_ == bytes_.size()) return {};
    value_pos_ = pos_;
    context_.clear();
    return Fail(std::to_string(bytes_.size() - pos_) +
                " bytes of unexpected data after the last element");
  }

  // An error located at the last value read.
  Error Fail(const std::string& what) const {
    return MakeError(ErrorCode::kParseError, std::string(name_) + ": byte " +
                                                 std::to_string(value_pos_) + ": " +
                                                 (context_.empty() ? "" : context_ + ": ") + what);
  }

 private:
  std::string_view bytes_;
  size_t pos_;
  size_t value_pos_ = 0;
  ByteOrder order_;
  std::string_view name_;
  std::string context_;
};

// Values from the body of an ascii file: one element per line, blank lines skipped.
class AsciiSource {
 public:
  AsciiSource(std::string_view bytes, size_t offset, size_t first_line, std::string_view name)
      : bytes_(bytes), pos_(offset), line_number_(first_line - 1), name_(name) {}

  Result<void> BeginElement(const std::string& element, uint64_t index) {
    context_ = element + " " + std::to_string(index);
    values_on_line_ = 0;
    cursor_ = 0;
    while (pos_ < bytes_.size()) {
      ++line_number_;
      line_ = internal::NextLine(bytes_, &pos_);
      if (line_.find_first_not_of(" \t\r\v\f") != std::string_view::npos) return {};
    }
    return Fail("truncated: file ends before this element");
  }

  Result<void> EndElement() {
    const std::string_view extra = NextToken(line_, &cursor_);
    if (extra.empty()) return {};
    return Fail("unexpected value " + Quote(extra) + " after " + std::to_string(values_on_line_) +
                " values");
  }

  Result<double> Scalar(PlyType type) {
    const std::string_view token = NextToken(line_, &cursor_);
    if (token.empty()) {
      return Fail("line ends after " + std::to_string(values_on_line_) + " values");
    }
    ++values_on_line_;
    if (IsInteger(type)) {
      int64_t value = 0;
      if (internal::ParseInt64(token, &value) != NumberStatus::kOk) {
        return Fail("value " + Quote(token) + " is not an integer (type " + NameOf(type) + ")");
      }
      const auto [low, high] = RangeOf(type);
      if (value < low || value > high) {
        return Fail("value " + Quote(token) + " is out of range for type " + NameOf(type));
      }
      return static_cast<double>(value);
    }
    double value = 0;
    const NumberStatus status = internal::ParseDouble(token, &value);
    if (status == NumberStatus::kOutOfRange) {
      return Fail("value " + Quote(token) + " is out of double range");
    }
    if (status != NumberStatus::kOk) return Fail("value " + Quote(token) + " is not a number");
    return value;
  }

  // Checks that a list of `count` values can fit on the rest of the line.
  Result<void> CheckListFits(PlyType /*type*/, uint64_t count) {
    if (count > (line_.size() - cursor_ + 1) / 2) {
      return Fail("list of " + std::to_string(count) + " values does not fit on the line");
    }
    return {};
  }

  Result<void> SkipList(PlyType type, uint64_t count) {
    if (Result<void> status = CheckListFits(type, count); !status.ok()) return status;
    for (uint64_t i = 0; i < count; ++i) {
      if (Result<double> value = Scalar(type); !value.ok()) return value.error();
    }
    return {};
  }

  Result<void> Finish() {
    while (pos_ < bytes_.size()) {
      ++line_number_;
      const std::string_view line = internal::NextLine(bytes_, &pos_);
      if (line.find_first_not_of(" \t\r\v\f") != std::string_view::npos) {
        context_.clear();
        return Fail("unexpected data after the last element");
      }
    }
    return {};
  }

  Error Fail(const std::string& what) const {
    return MakeError(ErrorCode::kParseError, std::string(name_) + ":" +
                                                 std::to_string(line_number_) + ": " +
                                                 (context_.empty() ? "" : context_ + ": ") + what);
  }

 private:
  std::string_view bytes_;
  size_t pos_;
  size_t line_number_;
  std::string_view name_;
  std::string_view line_;
  size_t cursor_ = 0;
  size_t values_on_line_ = 0;
  std::string context_;
};

// Reads every element in header order, keeping vertex positions and face triangles.
template <typename Source>
Result<Mesh> ReadBody(const Header& header, Source& source) {
  const Element& vertex = header.elements[header.vertex_element];
  Mesh mesh;
  // Safe: CheckCountsAgainstSize bounded the count by the file size (at most 4 bytes reserved
  // per byte of file). Triangles grow as they are read.
  mesh.p_MV.reserve(vertex.count);
  for (size_t e = 0; e < header.elements.size(); ++e) {
    const Element& element = header.elements[e];
    const bool is_vertex = static_cast<int>(e) == header.vertex_element;
    const bool is_face = static_cast<int>(e) == header.face_element;
    for (uint64_t k = 0; k < element.count; ++k) {
      if (Result<void> status = source.BeginElement(element.name, k); !status.ok()) {
        return status.error();
      }
      Eigen::Vector3d p_MV = Eigen::Vector3d::Zero();
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const Property& property = element.properties[p];
        const int prop = static_cast<int>(p);
        if (!property.is_list) {
          const Result<double> value = source.Scalar(property.type);
          if (!value.ok()) return value.error();
          if (is_vertex && (prop == header.x || prop == header.y || prop == header.z)) {
            if (!std::isfinite(*value)) {
              return source.Fail("coordinate '" + property.name + "' is not finite (" +
                                 internal::FormatDouble(*value) + ")");
            }
            p_MV[prop == header.x ? 0 : prop == header.y ? 1 : 2] = *value;
          }
          continue;
        }
        // A list: its count first.
        const Result<double> count = source.Scalar(property.type);
        if (!count.ok()) return count.error();
        if (*count < 0) {
          return source.Fail("list '" + property.name + "' has negative count " +
                             internal::FormatDouble(*count));
        }
        const uint64_t size = static_cast<uint64_t>(*count);
        if (Result<void> status = source.CheckListFits(property.item_type, size); !status.ok()) {
          return status.error();
        }
        if (!(is_face && prop == header.indices)) {
          if (Result<void> status = source.SkipList(property.item_type, size); !status.ok()) {
            return status.error();
          }
          continue;
        }
        // The face's vertex indices, fan-triangulated.
        if (size < 3) {
          return source.Fail("face has " + std::to_string(size) +
                             " vertex indices (need at least 3)");
        }
        if (mesh.triangles.size() + (size - 2) > kMaxMeshElements) {
          Error error = source.Fail("more than 2^31-1 triangles");
          error.code = ErrorCode::kLimitExceeded;
          return error;
        }
        uint32_t first = 0;
        uint32_t previous = 0;
        for (uint64_t i = 0; i < size; ++i) {
          const Result<double> index = source.Scalar(property.item_type);
          if (!index.ok()) return index.error();
          if (*index < 0 || *index >= static_cast<double>(vertex.count)) {
            return source.Fail("vertex index " + internal::FormatDouble(*index) +
                               " out of range (" + std::to_string(vertex.count) + " vertices)");
          }
          const uint32_t current = static_cast<uint32_t>(*index);
          if (i == 0) first = current;
          if (i >= 2) mesh.triangles.push_back({first, previous, current});
          previous = current;
        }
      }
      if (Result<void> status = source.EndElement(); !status.ok()) return status.error();
      if (is_vertex) mesh.p_MV.push_back(p_MV);
    }
  }
  if (Result<void> status = source.Finish(); !status.ok()) return status.error();
  return mesh;
}

}  // namespace

Result<Mesh> ReadPly(std::string_view bytes, std::string_view name_for_errors) {
  // Header, then counts against the file size, then the body.
  Result<Header> header = HeaderParser(bytes, name_for_errors).Parse();
  if (!header.ok()) return header.error();
  if (Result<void> status = CheckCountsAgainstSize(*header, bytes, name_for_errors); !status.ok()) {
    return status.error();
  }
  const Element& vertex = header->elements[header->vertex_element];
  if (vertex.count > kMaxMeshElements) {
    return MakeError(ErrorCode::kLimitExceeded, std::string(name_for_errors) + ":" +
                                                    std::to_string(vertex.header_line) +
                                                    ": more than 2^31-1 vertices");
  }
  if (header->format == PlyFormat::kAscii) {
    AsciiSource source(bytes, header->body_offset, header->body_first_line, name_for_errors);
    return ReadBody(*header, source);
  }
  BinarySource source(
      bytes, header->body_offset,
      header->format == PlyFormat::kBinaryLittle ? ByteOrder::kLittle : ByteOrder::kBig,
      name_for_errors);
  return ReadBody(*header, source);
}

Result<Mesh> ReadPly(const std::filesystem::path& path) {
  Result<std::string> bytes = internal::ReadFileBytes(path);
  if (!bytes.ok()) return bytes.error();
  return ReadPly(*bytes, path.string());
}

}  // namespace far
