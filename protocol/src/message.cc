#include "far/protocol/message.h"

#include <algorithm>
#include <array>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <span>

namespace far::protocol {
namespace {

// How one field of an LCM type is encoded (LCM 1.3.1, big-endian):
//   kScalar       `width` bytes (booleans and bytes 1, int32 4, int64 and double 8, byte[32] 32)
//   kCount        an int32 that other fields use as their length
//   kArray        `count` elements of `width` bytes; `count` is the index of its kCount field
//   kString       int32 length (including the NUL), then the bytes and the NUL
//   kStringArray  `count` strings
enum class FieldKind : uint8_t { kScalar, kCount, kArray, kString, kStringArray };

struct FieldSpec {
  const char* name;
  FieldKind kind;
  uint8_t width = 0;
  uint8_t count = 0;
};

constexpr FieldSpec Scalar(const char* name, uint8_t width) {
  return {name, FieldKind::kScalar, width, 0};
}
constexpr FieldSpec Count(const char* name) { return {name, FieldKind::kCount, 4, 0}; }
constexpr FieldSpec Array(const char* name, uint8_t width, uint8_t count_field) {
  return {name, FieldKind::kArray, width, count_field};
}
constexpr FieldSpec String(const char* name) { return {name, FieldKind::kString, 0, 0}; }
constexpr FieldSpec StringArray(const char* name, uint8_t count_field) {
  return {name, FieldKind::kStringArray, 0, count_field};
}

// The schemas mirror protocol/lcm/*.lcm field by field. A drift makes the round-trip tests in
// tests/protocol/message_test.cc fail (the pre-scan must consume exactly the encoded bytes of
// messages with every array and string filled).
constexpr std::array kOpenSession{
    Scalar("protocol_version", 4),  Scalar("request_id", 8),       String("client_name"),
    Scalar("update_ring_bytes", 8), Scalar("reply_ring_bytes", 8),
};
constexpr std::array kOpenSessionReply{
    Scalar("protocol_version", 4),
    Scalar("request_id", 8),
    Scalar("status", 4),
    String("status_name"),
    String("message"),
    Scalar("session_id", 8),
    Scalar("shm_bytes", 8),
    Scalar("ring_layout_version", 4),
    Scalar("update_ring_bytes", 8),
    Scalar("reply_ring_bytes", 8),
    String("lcm_url"),
    String("request_channel"),
    String("session_reply_channel"),
    Scalar("max_objects", 4),
    Scalar("max_vertices_per_object", 4),
    Scalar("max_triangles_per_object", 4),
    Scalar("max_reply_pairs", 8),
    Scalar("step_deadline_ms", 8),
};
constexpr std::array kSealed{
    Scalar("protocol_version", 4), Scalar("session_id", 8), Scalar("request_id", 8),
    Scalar("nonce", 24),           Count("box_bytes"),      Array("box", 1, 4),
};
constexpr std::array kStepStatus{
    Scalar("protocol_version", 4), Scalar("session_id", 8), Scalar("auth", 32),
    Scalar("request_id", 8),       Scalar("step_id", 8),    String("state"),
    Scalar("queue_position", 4),   String("stage"),         Scalar("elapsed_ms", 8),
};
constexpr std::array kStepRequest{
    Scalar("protocol_version", 4),
    Scalar("session_id", 8),
    Scalar("auth", 32),
    Scalar("request_id", 8),
    Scalar("step_id", 8),
    Scalar("ring_commit_sequence", 8),
    String("method"),
    String("mechanism"),
    String("output"),
    String("depth_format"),
    Scalar("resolution", 4),
    Scalar("subobject_size", 4),
    Scalar("has_distance", 1),
    Scalar("distance", 8),
    Scalar("geometry", 1),
    Scalar("timeout_ms", 4),
};
constexpr std::array kStepReply{
    Scalar("protocol_version", 4),           // 0
    Scalar("session_id", 8),                 // 1
    Scalar("auth", 32),                      // 2
    Scalar("request_id", 8),                 // 3
    Scalar("step_id", 8),                    // 4
    Scalar("ring_applied_sequence", 8),      // 5
    Scalar("status", 4),                     // 6
    String("status_name"),                   // 7
    String("message"),                       // 8
    String("output"),                        // 9
    String("method_run"),                    // 10
    String("method_reason"),                 // 11
    Scalar("reply_in_shm", 1),               // 12
    Scalar("shm_reply_sequence", 8),         // 13
    Scalar("shm_reply_index", 8),            // 14
    Scalar("shm_reply_bytes", 8),            // 15
    Scalar("shm_reply_hash", 32),            // 16
    Count("num_pcs_objects"),                // 17
    Array("pcs_objects", 8, 17),             // 18
    Count("num_object_pairs"),               // 19
    Array("object_pair_a", 8, 19),           // 20
    Array("object_pair_b", 8, 19),           // 21
    Count("num_pcs_primitive_objects"),      // 22
    Array("pcs_primitive_object", 8, 22),    // 23
    Array("pcs_primitive_count", 4, 22),     // 24
    Count("num_pcs_primitives"),             // 25
    Array("pcs_primitive_triangle", 4, 25),  // 26
    Count("num_contacts"),                   // 27
    Array("contact_object_a", 8, 27),        // 28
    Array("contact_triangle_a", 4, 27),      // 29
    Array("contact_object_b", 8, 27),        // 30
    Array("contact_triangle_b", 4, 27),      // 31
    Count("num_distance_pairs"),             // 32
    Array("distance_object_a", 8, 32),       // 33
    Array("distance_triangle_a", 4, 32),     // 34
    Array("distance_object_b", 8, 32),       // 35
    Array("distance_triangle_b", 4, 32),     // 36
    Array("distance", 8, 32),                // 37
    Count("num_contact_geometry"),           // 38
    Array("contact_point_count", 1, 38),     // 39
    Array("contact_coplanar", 1, 38),        // 40
    Count("num_contact_point_coords"),       // 41
    Array("contact_points", 8, 41),          // 42
    Count("num_contact_normal_coords"),      // 43
    Array("contact_normal_a", 8, 43),        // 44
    Array("contact_normal_b", 8, 43),        // 45
    Count("num_closest_point_coords"),       // 46
    Array("closest_point_a", 8, 46),         // 47
    Array("closest_point_b", 8, 46),         // 48
    Count("num_penetrations"),               // 49
    Array("penetration_object_a", 8, 49),    // 50
    Array("penetration_object_b", 8, 49),    // 51
    Array("penetration_closed", 1, 49),      // 52
    Array("penetration_depth", 8, 49),       // 53
    Count("num_penetration_coords"),         // 54
    Array("penetration_direction", 8, 54),   // 55
    Array("penetration_point_a", 8, 54),     // 56
    Array("penetration_point_b", 8, 54),     // 57
    Count("num_stages"),                     // 58
    StringArray("stage_name", 58),           // 59
    Array("stage_ms", 8, 58),                // 60
    Scalar("total_ms", 8),                   // 61
    Scalar("primitives_rendered", 8),        // 62
    Scalar("draws", 8),                      // 63
    Scalar("queries", 8),                    // 64
    Scalar("bytes_uploaded", 8),             // 65
    Scalar("object_pairs_considered", 8),    // 66
    Scalar("pairs_considered", 8),           // 67
    Scalar("pairs_tested", 8),               // 68
    Scalar("object_radius", 8),              // 69
    Scalar("primitive_radius", 8),           // 70
    Scalar("guaranteed", 1),                 // 71
    String("guarantee_basis"),               // 72
    Count("num_levels"),                     // 73
    StringArray("level_name", 73),           // 74
    Array("level_views", 4, 73),             // 75
    Array("level_resolution", 4, 73),        // 76
    Array("level_offset_radius", 8, 73),     // 77
    Array("level_pixel_size", 8, 73),        // 78
    Array("level_depth_step", 8, 73),        // 79
    Array("level_rounding", 8, 73),          // 80
    Array("level_world_min_x", 8, 73),       // 81
    Array("level_world_min_y", 8, 73),       // 82
    Array("level_world_min_z", 8, 73),       // 83
    Array("level_world_max_x", 8, 73),       // 84
    Array("level_world_max_y", 8, 73),       // 85
    Array("level_world_max_z", 8, 73),       // 86
};
// The pre-scanner keeps every count it reads by field index: no schema may have more fields.
// (Protocol version 4's step_reply_t has 87; the array was 64 before, and UBSan caught the
// scanner writing past it.)
constexpr size_t kMaxSchemaFields = 128;
constexpr std::array kError{
    Scalar("protocol_version", 4),
    Scalar("session_id", 8),
    Scalar("auth", 32),
    Scalar("request_id", 8),
    Scalar("status", 4),
    String("status_name"),
    String("message"),
    Scalar("session_closed", 1),
};
constexpr std::array kStatusRequest{
    Scalar("protocol_version", 4),
    Scalar("request_id", 8),
};
constexpr std::array kStatusReply{
    Scalar("protocol_version", 4),           // 0
    Scalar("request_id", 8),                 // 1
    String("daemon_version"),                // 2
    String("daemon_name"),                   // 3
    String("gl_renderer"),                   // 4
    String("gl_device"),                     // 5
    String("lcm_url"),                       // 6
    String("channel_prefix"),                // 7
    Scalar("uptime_ms", 8),                  // 8
    Scalar("max_sessions", 4),               // 9
    Scalar("max_sessions_per_user", 4),      // 10
    Scalar("sessions_open", 4),              // 11
    Scalar("steps_total", 8),                // 12
    Scalar("errors_total", 8),               // 13
    Scalar("rejected_messages_total", 8),    // 14
    Scalar("latency_p50_ms", 8),             // 15
    Scalar("latency_p90_ms", 8),             // 16
    Scalar("latency_p99_ms", 8),             // 17
    Scalar("latency_max_ms", 8),             // 18
    Scalar("latency_samples", 8),            // 19
    Count("num_sessions"),                   // 20
    Array("session_id", 8, 20),              // 21
    Array("session_uid", 4, 20),             // 22
    StringArray("session_client_name", 20),  // 23
    Array("session_steps", 8, 20),           // 24
    Array("session_objects", 4, 20),         // 25
    Array("session_triangles", 8, 20),       // 26
    Array("session_latency_p50_ms", 8, 20),  // 27
    Array("session_latency_p99_ms", 8, 20),  // 28
    Count("num_error_kinds"),                // 29
    StringArray("error_kind", 29),           // 30
    Array("error_count", 8, 29),             // 31
    Scalar("daemon_pid", 4),                 // 32
    Scalar("opens_refused_total", 8),        // 33
    Scalar("memory_rss_bytes", 8),           // 34
    Scalar("segment_bytes", 8),              // 35
    Count("num_gpu_names"),                  // 36
    StringArray("gpu_name", 36),             // 37
    Count("num_methods"),                    // 38
    StringArray("method_name", 38),          // 39
    Array("method_steps", 8, 38),            // 40
    Array("session_pid", 4, 20),             // 41
};

constexpr std::array kRecordingHeader{
    Scalar("protocol_version", 4), Scalar("format_version", 4), String("far_version"),
    String("client_name"),         String("daemon_name"),       String("gl_renderer"),
    Scalar("session_id", 8),       Scalar("start_time_us", 8),
};
constexpr std::array kRingRecord{
    Scalar("protocol_version", 4),  // 0
    Scalar("sequence", 8),          // 1
    Scalar("step_id", 8),           // 2
    Scalar("type", 4),              // 3
    Scalar("object_id", 8),         // 4
    Scalar("motion", 4),            // 5
    Scalar("X_WO", 56),             // 6
    Count("num_coordinates"),       // 7
    Array("p_MV", 8, 7),            // 8
    Count("num_indices"),           // 9
    Array("triangles", 4, 9),       // 10
};
static_assert(kOpenSession.size() <= kMaxSchemaFields &&
              kOpenSessionReply.size() <= kMaxSchemaFields && kSealed.size() <= kMaxSchemaFields &&
              kStepStatus.size() <= kMaxSchemaFields && kStepRequest.size() <= kMaxSchemaFields &&
              kStepReply.size() <= kMaxSchemaFields && kError.size() <= kMaxSchemaFields &&
              kStatusRequest.size() <= kMaxSchemaFields &&
              kStatusReply.size() <= kMaxSchemaFields &&
              kRecordingHeader.size() <= kMaxSchemaFields &&
              kRingRecord.size() <= kMaxSchemaFields);

struct TypeInfo {
  MessageType type;
  std::string_view name;
  int64_t (*hash)();
  std::span<const FieldSpec> schema;
};

const std::array<TypeInfo, 11>& Types() {
  static const std::array<TypeInfo, 11> types{{
      {MessageType::kOpenSession, "open_session_t", &far_lcm::open_session_t::getHash,
       kOpenSession},
      {MessageType::kOpenSessionReply, "open_session_reply_t",
       &far_lcm::open_session_reply_t::getHash, kOpenSessionReply},
      {MessageType::kSealed, "sealed_t", &far_lcm::sealed_t::getHash, kSealed},
      {MessageType::kStepStatus, "step_status_t", &far_lcm::step_status_t::getHash, kStepStatus},
      {MessageType::kStepRequest, "step_request_t", &far_lcm::step_request_t::getHash,
       kStepRequest},
      {MessageType::kStepReply, "step_reply_t", &far_lcm::step_reply_t::getHash, kStepReply},
      {MessageType::kError, "error_t", &far_lcm::error_t::getHash, kError},
      {MessageType::kStatusRequest, "status_request_t", &far_lcm::status_request_t::getHash,
       kStatusRequest},
      {MessageType::kStatusReply, "status_reply_t", &far_lcm::status_reply_t::getHash,
       kStatusReply},
      {MessageType::kRecordingHeader, "recording_header_t", &far_lcm::recording_header_t::getHash,
       kRecordingHeader},
      {MessageType::kRingRecord, "ring_record_t", &far_lcm::ring_record_t::getHash, kRingRecord},
  }};
  return types;
}

const TypeInfo& InfoOf(MessageType type) {
  for (const TypeInfo& info : Types()) {
    if (info.type == type) return info;
  }
  return Types()[0];  // unreachable: every enumerator has an entry
}

int64_t ReadBigEndian(const uint8_t* p, int bytes) {
  uint64_t value = 0;
  for (int i = 0; i < bytes; ++i) value = (value << 8) | p[i];
  if (bytes == 4) return static_cast<int32_t>(static_cast<uint32_t>(value));
  return static_cast<int64_t>(value);
}

std::string Hex(int64_t value) {
  char text[32];
  std::snprintf(text, sizeof(text), "0x%016" PRIx64, static_cast<uint64_t>(value));
  return text;
}

Error ParseError(std::string_view type, const FieldSpec& field, const std::string& what) {
  return MakeError(ErrorCode::kParseError, std::string(type) + "." + field.name + ": " + what);
}

// Walks the encoding after the fingerprint and proves that every length fits: the fields in
// schema order, each checked against the bytes left; the counts read so far size the arrays
// after them.
class PreScanner {
 public:
  PreScanner(const TypeInfo& info, const uint8_t* data, size_t size)
      : info_(info), data_(data), size_(size) {}

  Result<void> Run() {
    for (size_t i = 0; i < info_.schema.size(); ++i) {
      const FieldSpec& field = info_.schema[i];
      Result<void> ok;
      switch (field.kind) {
        case FieldKind::kScalar:
        case FieldKind::kCount:
          ok = Scalar(field, i);
          break;
        case FieldKind::kArray:
          ok = Array(field);
          break;
        case FieldKind::kString:
          ok = String(field, "");
          break;
        case FieldKind::kStringArray:
          ok = StringArray(field);
          break;
      }
      if (!ok) return ok;
    }
    if (pos_ != size_) {
      return MakeError(ErrorCode::kParseError, std::string(info_.name) + ": " +
                                                   std::to_string(size_ - pos_) +
                                                   " trailing bytes after the last field");
    }
    return {};
  }

 private:
  size_t left() const { return size_ - pos_; }

  // A fixed-width field; a count (field i) is kept for the arrays that follow.
  Result<void> Scalar(const FieldSpec& field, size_t i) {
    if (left() < field.width) {
      return ParseError(info_.name, field,
                        "needs " + std::to_string(field.width) + " bytes, " +
                            std::to_string(left()) + " left (truncated)");
    }
    if (field.kind == FieldKind::kCount) {
      const int64_t count = ReadBigEndian(data_ + pos_, 4);
      if (count < 0) return ParseError(info_.name, field, std::to_string(count) + " is negative");
      counts_[i] = count;
    }
    pos_ += field.width;
    return {};
  }

  Result<void> Array(const FieldSpec& field) {
    // 64-bit arithmetic: count < 2^31 and width <= 8, no overflow.
    const uint64_t count = static_cast<uint64_t>(counts_[field.count]);
    const uint64_t bytes = count * field.width;
    if (bytes > left()) {
      return ParseError(info_.name, field,
                        std::to_string(count) + " elements of " + std::to_string(field.width) +
                            " bytes need " + std::to_string(bytes) + " bytes, " +
                            std::to_string(left()) + " left (" + info_.schema[field.count].name +
                            " is too large)");
    }
    pos_ += static_cast<size_t>(bytes);
    return {};
  }

  // An LCM string: a 4-byte length that counts its final NUL, then the bytes, NUL only last.
  Result<void> String(const FieldSpec& field, std::string_view element) {
    if (left() < 4) {
      return ParseError(info_.name, field,
                        std::string(element) + "string length needs 4 bytes, " +
                            std::to_string(left()) + " left");
    }
    const int64_t length = ReadBigEndian(data_ + pos_, 4);
    pos_ += 4;
    if (length < 1) {
      return ParseError(info_.name, field,
                        std::string(element) + "string length " + std::to_string(length) +
                            " is less than 1 (LCM strings include their NUL)");
    }
    if (static_cast<uint64_t>(length) > left()) {
      return ParseError(info_.name, field,
                        std::string(element) + "string length " + std::to_string(length) +
                            " runs past the end (" + std::to_string(left()) + " bytes left)");
    }
    const auto* text = reinterpret_cast<const char*>(data_ + pos_);
    if (text[length - 1] != '\0') {
      return ParseError(info_.name, field, std::string(element) + "string lacks its final NUL");
    }
    if (std::memchr(text, '\0', static_cast<size_t>(length - 1)) != nullptr) {
      return ParseError(info_.name, field, std::string(element) + "string contains a NUL");
    }
    pos_ += static_cast<size_t>(length);
    return {};
  }

  Result<void> StringArray(const FieldSpec& field) {
    const int64_t count = counts_[field.count];
    // Each string takes at least 5 bytes; check before walking so a huge count fails fast.
    if (static_cast<uint64_t>(count) * 5 > left()) {
      return ParseError(info_.name, field,
                        std::to_string(count) + " strings need at least " +
                            std::to_string(count * 5) + " bytes, " + std::to_string(left()) +
                            " left (" + info_.schema[field.count].name + " is too large)");
    }
    for (int64_t k = 0; k < count; ++k) {
      if (auto ok = String(field, "[" + std::to_string(k) + "] "); !ok) return ok.error();
    }
    return {};
  }

  const TypeInfo& info_;
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 8;                                  // after the fingerprint
  std::array<int64_t, kMaxSchemaFields> counts_{};  // by field index: the counts read so far
};

Result<void> PreScan(const TypeInfo& info, const uint8_t* data, size_t size) {
  return PreScanner(info, data, size).Run();
}

}  // namespace

std::string_view ToString(MessageType type) { return InfoOf(type).name; }

Result<MessageType> IdentifyMessage(const void* data, size_t size) {
  if (data == nullptr || size < 8) {
    return MakeError(ErrorCode::kParseError, "message: " + std::to_string(size) +
                                                 " bytes is too short for an LCM fingerprint");
  }
  const int64_t fingerprint = ReadBigEndian(static_cast<const uint8_t*>(data), 8);
  for (const TypeInfo& info : Types()) {
    if (info.hash() == fingerprint) return info.type;
  }
  return MakeError(ErrorCode::kParseError,
                   "message: fingerprint " + Hex(fingerprint) + " is not a far_lcm type");
}

namespace internal {

Result<void> CheckEncoding(MessageType type, const void* data, size_t size, size_t max_size) {
  const TypeInfo& info = InfoOf(type);
  const std::string name(info.name);
  // 1. The size, before anything else looks at the bytes.
  const size_t cap = std::min<size_t>(max_size, static_cast<size_t>(INT32_MAX));
  if (size > cap) {
    return MakeError(ErrorCode::kLimitExceeded, name + ": " + std::to_string(size) +
                                                    " bytes is over the " + std::to_string(cap) +
                                                    "-byte cap");
  }
  if (data == nullptr || size < 8) {
    return MakeError(ErrorCode::kParseError,
                     name + ": " + std::to_string(size) + " bytes is too short (truncated)");
  }
  // 2. The fingerprint.
  const auto* bytes = static_cast<const uint8_t*>(data);
  const int64_t fingerprint = ReadBigEndian(bytes, 8);
  if (fingerprint != info.hash()) {
    return MakeError(ErrorCode::kParseError, name + ": fingerprint " + Hex(fingerprint) +
                                                 " does not match " + name + "'s " +
                                                 Hex(info.hash()));
  }
  // 3. Every length against the bytes that are there.
  return PreScan(info, bytes, size);
}

Result<void> CheckProtocolVersion(MessageType type, int32_t version) {
  if (version != kProtocolVersion) {
    return MakeError(ErrorCode::kVersionMismatch, std::string(ToString(type)) +
                                                      ".protocol_version: got " +
                                                      std::to_string(version) + ", expected " +
                                                      std::to_string(kProtocolVersion));
  }
  return {};
}

}  // namespace internal
}  // namespace far::protocol
