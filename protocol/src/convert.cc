#include "far/protocol/convert.h"

#include <climits>
#include <cstring>

#include "far/base/limits.h"
#include "far/protocol/version.h"

namespace far::protocol {
namespace {

constexpr int kNumErrorCodes = static_cast<int>(ErrorCode::kInternal) + 1;

// Sets status, status_name and message of any reply-like message.
template <typename M>
void SetStatus(M& message, const Error* error) {
  if (error == nullptr) {
    message.status = kWireOk;
    message.status_name = "ok";
    message.message.clear();
  } else {
    message.status = ToWireStatus(error->code);
    message.status_name = ToString(error->code);
    message.message = error->message;
  }
}

far_lcm::step_reply_t EmptyReply(const StepReplyIds& ids) {
  far_lcm::step_reply_t reply{};
  reply.protocol_version = kProtocolVersion;
  reply.session_id = ids.session_id;
  std::memset(reply.auth, 0, sizeof(reply.auth));
  reply.request_id = ids.request_id;
  reply.step_id = ids.step_id;
  reply.ring_applied_sequence = static_cast<int64_t>(ids.ring_applied_sequence);
  reply.reply_in_shm = false;
  reply.shm_reply_sequence = 0;
  reply.shm_reply_index = 0;
  reply.shm_reply_bytes = 0;
  std::memset(reply.shm_reply_hash, 0, sizeof(reply.shm_reply_hash));
  reply.num_pcs_objects = 0;
  reply.num_object_pairs = 0;
  reply.num_pcs_primitive_objects = 0;
  reply.num_pcs_primitives = 0;
  reply.num_contacts = 0;
  reply.num_distance_pairs = 0;
  reply.num_contact_geometry = 0;
  reply.num_contact_point_coords = 0;
  reply.num_contact_normal_coords = 0;
  reply.num_closest_point_coords = 0;
  reply.num_penetrations = 0;
  reply.num_penetration_coords = 0;
  reply.num_stages = 0;
  reply.total_ms = 0;
  reply.primitives_rendered = 0;
  reply.draws = 0;
  reply.queries = 0;
  reply.bytes_uploaded = 0;
  reply.object_pairs_considered = 0;
  reply.pairs_considered = 0;
  reply.pairs_tested = 0;
  reply.object_radius = 0;
  reply.primitive_radius = 0;
  reply.guaranteed = false;
  reply.num_levels = 0;
  return reply;
}

Error TooMany(std::string_view what, size_t count) {
  return MakeError(ErrorCode::kLimitExceeded, "step_reply_t." + std::string(what) + ": " +
                                                  std::to_string(count) +
                                                  " entries exceed the wire limit");
}

Error BadReply(std::string_view field, const std::string& what) {
  return MakeError(ErrorCode::kParseError, "step_reply_t." + std::string(field) + ": " + what);
}

}  // namespace

int32_t ToWireStatus(ErrorCode code) { return static_cast<int32_t>(code) + 1; }

ErrorCode FromWireStatus(int32_t status) {
  if (status < 1 || status > kNumErrorCodes) return ErrorCode::kInternal;
  return static_cast<ErrorCode>(status - 1);
}

far_lcm::step_request_t MakeStepRequest(int64_t session_id, int64_t request_id, int64_t step_id,
                                        uint64_t ring_commit_sequence, const StepRequest& request,
                                        int32_t timeout_ms) {
  far_lcm::step_request_t message{};
  message.protocol_version = kProtocolVersion;
  message.session_id = session_id;
  std::memset(message.auth, 0, sizeof(message.auth));
  message.request_id = request_id;
  message.step_id = step_id;
  message.ring_commit_sequence = static_cast<int64_t>(ring_commit_sequence);
  message.method = ToString(request.method);
  message.mechanism = ToString(request.mechanism);
  message.output = ToString(request.output);
  message.depth_format = ToString(request.depth_format);
  message.resolution = request.resolution;
  message.subobject_size = request.subobject_size;
  message.has_distance = request.distance.has_value();
  message.distance = request.distance.value_or(0.0);
  message.geometry = request.geometry;
  message.timeout_ms = timeout_ms;
  return message;
}

namespace {

// The wire bytes of a result's contact geometry.
uint64_t GeometryBytes(const StepResult& result) {
  uint64_t bytes =
      48 * uint64_t{result.closest_points.size()} + 97 * uint64_t{result.penetrations.size()};
  for (const ContactGeometry& g : result.contact_geometry) {
    bytes += 50 + 24 * static_cast<uint64_t>(g.num_points);
  }
  return bytes;
}

// Checks the size of a result's arrays against the reply cap and the wire's int32 counts,
// before anything is allocated.
Result<void> CheckReplySize(const StepResult& result) {
  size_t primitive_total = 0;
  for (const auto& [id, triangles] : result.pcs_primitives) primitive_total += triangles.size();
  const uint64_t array_bytes =
      8 * uint64_t{result.pcs_objects.size()} + 16 * uint64_t{result.object_pairs.size()} +
      12 * uint64_t{result.pcs_primitives.size()} + 4 * uint64_t{primitive_total} +
      24 * uint64_t{result.contacts.size()} + 32 * uint64_t{result.distance_pairs.size()} +
      GeometryBytes(result);
  if (array_bytes > kMaxStepReplyBytes - 4096) {
    return MakeError(ErrorCode::kLimitExceeded, "step_reply_t: " + std::to_string(array_bytes) +
                                                    " bytes of results exceed the " +
                                                    std::to_string(kMaxStepReplyBytes) +
                                                    "-byte reply cap");
  }
  for (const auto& [what, count] :
       {std::pair<const char*, size_t>{"pcs_objects", result.pcs_objects.size()},
        {"object_pairs", result.object_pairs.size()},
        {"pcs_primitive_object", result.pcs_primitives.size()},
        {"pcs_primitive_triangle", primitive_total},
        {"contacts", result.contacts.size()},
        {"distance_pairs", result.distance_pairs.size()},
        {"stages", result.stats.stages.size()}}) {
    if (count > INT32_MAX) return TooMany(what, count);
  }
  return {};
}

// Object ids travel as int64 (every uint32 fits); triangle indices as int32, which every index
// of a valid mesh fits (at most kMaxMeshElements triangles).
int64_t WireId(uint32_t id) { return static_cast<int64_t>(id); }
int32_t WireIndex(uint32_t index, bool* overflow) {
  if (index > INT32_MAX) *overflow = true;
  return static_cast<int32_t>(index);
}

// The object PCS, the object pairs and the primitive PCS.
void SetCullingArrays(far_lcm::step_reply_t& reply, const StepResult& result, bool* overflow) {
  reply.num_pcs_objects = static_cast<int32_t>(result.pcs_objects.size());
  for (const uint32_t object : result.pcs_objects) reply.pcs_objects.push_back(WireId(object));
  reply.num_object_pairs = static_cast<int32_t>(result.object_pairs.size());
  for (const ObjectPair& pair : result.object_pairs) {
    reply.object_pair_a.push_back(WireId(pair.object_a));
    reply.object_pair_b.push_back(WireId(pair.object_b));
  }
  reply.num_pcs_primitive_objects = static_cast<int32_t>(result.pcs_primitives.size());
  int32_t total = 0;
  for (const auto& [object, triangles] : result.pcs_primitives) {
    reply.pcs_primitive_object.push_back(WireId(object));
    reply.pcs_primitive_count.push_back(static_cast<int32_t>(triangles.size()));
    for (const uint32_t t : triangles)
      reply.pcs_primitive_triangle.push_back(WireIndex(t, overflow));
    total += static_cast<int32_t>(triangles.size());
  }
  reply.num_pcs_primitives = total;
}

// The contact pairs and the distance pairs.
void SetPairArrays(far_lcm::step_reply_t& reply, const StepResult& result, bool* overflow) {
  reply.num_contacts = static_cast<int32_t>(result.contacts.size());
  for (const ContactPair& pair : result.contacts) {
    reply.contact_object_a.push_back(WireId(pair.object_a));
    reply.contact_triangle_a.push_back(WireIndex(pair.triangle_a, overflow));
    reply.contact_object_b.push_back(WireId(pair.object_b));
    reply.contact_triangle_b.push_back(WireIndex(pair.triangle_b, overflow));
  }
  reply.num_distance_pairs = static_cast<int32_t>(result.distance_pairs.size());
  for (const DistancePair& pair : result.distance_pairs) {
    reply.distance_object_a.push_back(WireId(pair.pair.object_a));
    reply.distance_triangle_a.push_back(WireIndex(pair.pair.triangle_a, overflow));
    reply.distance_object_b.push_back(WireId(pair.pair.object_b));
    reply.distance_triangle_b.push_back(WireIndex(pair.pair.triangle_b, overflow));
    reply.distance.push_back(pair.distance);
  }
}

void PushPoint(std::vector<double>& coords, const Eigen::Vector3d& p) {
  coords.insert(coords.end(), {p.x(), p.y(), p.z()});
}

// The contact geometry, when the step computed it.
void SetGeometryArrays(far_lcm::step_reply_t& reply, const StepResult& result) {
  reply.num_contact_geometry = static_cast<int32_t>(result.contact_geometry.size());
  for (const ContactGeometry& g : result.contact_geometry) {
    reply.contact_point_count.push_back(static_cast<int8_t>(g.num_points));
    reply.contact_coplanar.push_back(g.coplanar);
    for (int k = 0; k < g.num_points; ++k) PushPoint(reply.contact_points, g.points[k]);
    PushPoint(reply.contact_normal_a, g.normal_a);
    PushPoint(reply.contact_normal_b, g.normal_b);
  }
  reply.num_contact_point_coords = static_cast<int32_t>(reply.contact_points.size());
  reply.num_contact_normal_coords = static_cast<int32_t>(reply.contact_normal_a.size());
  for (const ClosestPoints& c : result.closest_points) {
    PushPoint(reply.closest_point_a, c.point_a);
    PushPoint(reply.closest_point_b, c.point_b);
  }
  reply.num_closest_point_coords = static_cast<int32_t>(reply.closest_point_a.size());
  reply.num_penetrations = static_cast<int32_t>(result.penetrations.size());
  for (const Penetration& p : result.penetrations) {
    reply.penetration_object_a.push_back(WireId(p.object_a));
    reply.penetration_object_b.push_back(WireId(p.object_b));
    reply.penetration_closed.push_back(p.closed);
    reply.penetration_depth.push_back(p.depth);
    PushPoint(reply.penetration_direction, p.direction);
    PushPoint(reply.penetration_point_a, p.point_a);
    PushPoint(reply.penetration_point_b, p.point_b);
  }
  reply.num_penetration_coords = static_cast<int32_t>(reply.penetration_direction.size());
}

void SetStats(far_lcm::step_reply_t& reply, const StepStats& stats) {
  reply.method_run = stats.method;
  reply.method_reason = stats.method_reason;
  reply.num_stages = static_cast<int32_t>(stats.stages.size());
  for (const StageStats& stage : stats.stages) {
    reply.stage_name.emplace_back(ToString(stage.stage));
    reply.stage_ms.push_back(stage.ms);
  }
  reply.total_ms = stats.total_ms;
  reply.primitives_rendered = stats.primitives_rendered;
  reply.draws = stats.draws;
  reply.queries = stats.queries;
  reply.bytes_uploaded = stats.bytes_uploaded;
  reply.object_pairs_considered = stats.object_pairs;
  reply.pairs_considered = stats.pairs_considered;
  reply.pairs_tested = stats.pairs_tested;
  reply.object_radius = stats.object_radius;
  reply.primitive_radius = stats.primitive_radius;
  const Certificate& certificate = stats.certificate;
  reply.guaranteed = certificate.guaranteed;
  reply.guarantee_basis = certificate.basis;
  reply.num_levels = static_cast<int32_t>(certificate.levels.size());
  for (const LevelCertificate& level : certificate.levels) {
    reply.level_name.push_back(level.level);
    reply.level_views.push_back(level.views);
    reply.level_resolution.push_back(level.resolution);
    reply.level_offset_radius.push_back(level.offset_radius);
    reply.level_pixel_size.push_back(level.pixel_size);
    reply.level_depth_step.push_back(level.depth_step);
    reply.level_rounding.push_back(level.rounding);
    reply.level_world_min_x.push_back(level.world_min[0]);
    reply.level_world_min_y.push_back(level.world_min[1]);
    reply.level_world_min_z.push_back(level.world_min[2]);
    reply.level_world_max_x.push_back(level.world_max[0]);
    reply.level_world_max_y.push_back(level.world_max[1]);
    reply.level_world_max_z.push_back(level.world_max[2]);
  }
}

}  // namespace

Result<far_lcm::step_reply_t> MakeStepReply(const StepReplyIds& ids, Output output,
                                            const StepResult& result) {
  if (auto ok = CheckReplySize(result); !ok) return ok.error();
  far_lcm::step_reply_t reply = EmptyReply(ids);
  SetStatus(reply, nullptr);
  reply.output = ToString(output);
  bool index_overflow = false;
  SetCullingArrays(reply, result, &index_overflow);
  SetPairArrays(reply, result, &index_overflow);
  SetGeometryArrays(reply, result);
  if (index_overflow) {
    return MakeError(ErrorCode::kInternal, "step_reply_t: a triangle index is over INT32_MAX");
  }
  SetStats(reply, result.stats);
  return reply;
}

far_lcm::step_reply_t MakeStepErrorReply(const StepReplyIds& ids, const Error& error) {
  far_lcm::step_reply_t reply = EmptyReply(ids);
  SetStatus(reply, &error);
  reply.output = "";
  return reply;
}

far_lcm::step_status_t MakeStepStatus(int64_t session_id, int64_t request_id, int64_t step_id,
                                      std::string_view state, int32_t queue_position,
                                      std::optional<Stage> stage, double elapsed_ms) {
  far_lcm::step_status_t message{};
  message.protocol_version = kProtocolVersion;
  message.session_id = session_id;
  std::memset(message.auth, 0, sizeof(message.auth));
  message.request_id = request_id;
  message.step_id = step_id;
  message.state = std::string(state);
  message.queue_position = queue_position;
  message.stage = stage ? std::string(ToString(*stage)) : "-";
  message.elapsed_ms = elapsed_ms;
  return message;
}

far_lcm::step_request_t MakeProbeRequest(int64_t session_id, int64_t request_id) {
  far_lcm::step_request_t message =
      MakeStepRequest(session_id, request_id, kProbeStepId, 0, StepRequest{});
  message.output = std::string(kProbeOutput);
  return message;
}

bool IsProbe(const far_lcm::step_request_t& message) { return message.output == kProbeOutput; }

far_lcm::error_t MakeErrorMessage(int64_t session_id, int64_t request_id, const Error& error,
                                  bool session_closed) {
  far_lcm::error_t message{};
  message.protocol_version = kProtocolVersion;
  message.session_id = session_id;
  std::memset(message.auth, 0, sizeof(message.auth));
  message.request_id = request_id;
  SetStatus(message, &error);
  message.session_closed = session_closed;
  return message;
}

namespace {

// Checks the contact geometry's counts against each other (the sizes are already checked).
Result<void> CheckGeometryArrays(const far_lcm::step_reply_t& reply) {
  if (reply.num_contact_geometry != 0 && reply.num_contact_geometry != reply.num_contacts) {
    return BadReply("num_contact_geometry",
                    std::to_string(reply.num_contact_geometry) + " is neither 0 nor num_contacts");
  }
  int64_t points = 0;
  for (size_t i = 0; i < reply.contact_point_count.size(); ++i) {
    const int count = reply.contact_point_count[i];
    if (count < 1 || count > ContactGeometry::kMaxPoints) {
      return BadReply("contact_point_count",
                      "[" + std::to_string(i) + "] = " + std::to_string(count) +
                          " is outside [1, " + std::to_string(ContactGeometry::kMaxPoints) + "]");
    }
    points += count;
  }
  const auto coords = [](int64_t n) { return 3 * n; };
  if (reply.num_contact_point_coords != coords(points) ||
      reply.num_contact_normal_coords != coords(reply.num_contact_geometry)) {
    return BadReply("num_contact_point_coords", "coordinates do not match the point counts");
  }
  if (reply.num_closest_point_coords != 0 &&
      reply.num_closest_point_coords != coords(reply.num_distance_pairs)) {
    return BadReply("num_closest_point_coords", "is neither 0 nor 3 x num_distance_pairs");
  }
  if (reply.num_penetration_coords != coords(reply.num_penetrations)) {
    return BadReply("num_penetration_coords", "is not 3 x num_penetrations");
  }
  return {};
}

// Whether every array of a reply is as long as its count says.
bool ArraysMatchTheirCounts(const far_lcm::step_reply_t& reply) {
  // A decoded reply has every array sized by its count; a hand-built one may not.
  const auto sized = [](size_t size, int32_t count) {
    return count >= 0 && size == static_cast<size_t>(count);
  };
  return sized(reply.pcs_objects.size(), reply.num_pcs_objects) &&
         sized(reply.object_pair_a.size(), reply.num_object_pairs) &&
         sized(reply.object_pair_b.size(), reply.num_object_pairs) &&
         sized(reply.pcs_primitive_object.size(), reply.num_pcs_primitive_objects) &&
         sized(reply.pcs_primitive_count.size(), reply.num_pcs_primitive_objects) &&
         sized(reply.pcs_primitive_triangle.size(), reply.num_pcs_primitives) &&
         sized(reply.contact_object_a.size(), reply.num_contacts) &&
         sized(reply.contact_triangle_a.size(), reply.num_contacts) &&
         sized(reply.contact_object_b.size(), reply.num_contacts) &&
         sized(reply.contact_triangle_b.size(), reply.num_contacts) &&
         sized(reply.distance_object_a.size(), reply.num_distance_pairs) &&
         sized(reply.distance_triangle_a.size(), reply.num_distance_pairs) &&
         sized(reply.distance_object_b.size(), reply.num_distance_pairs) &&
         sized(reply.distance_triangle_b.size(), reply.num_distance_pairs) &&
         sized(reply.distance.size(), reply.num_distance_pairs) &&
         sized(reply.contact_point_count.size(), reply.num_contact_geometry) &&
         sized(reply.contact_coplanar.size(), reply.num_contact_geometry) &&
         sized(reply.contact_points.size(), reply.num_contact_point_coords) &&
         sized(reply.contact_normal_a.size(), reply.num_contact_normal_coords) &&
         sized(reply.contact_normal_b.size(), reply.num_contact_normal_coords) &&
         sized(reply.closest_point_a.size(), reply.num_closest_point_coords) &&
         sized(reply.closest_point_b.size(), reply.num_closest_point_coords) &&
         sized(reply.penetration_object_a.size(), reply.num_penetrations) &&
         sized(reply.penetration_object_b.size(), reply.num_penetrations) &&
         sized(reply.penetration_closed.size(), reply.num_penetrations) &&
         sized(reply.penetration_depth.size(), reply.num_penetrations) &&
         sized(reply.penetration_direction.size(), reply.num_penetration_coords) &&
         sized(reply.penetration_point_a.size(), reply.num_penetration_coords) &&
         sized(reply.penetration_point_b.size(), reply.num_penetration_coords) &&
         sized(reply.stage_name.size(), reply.num_stages) &&
         sized(reply.stage_ms.size(), reply.num_stages);
}

// Object ids in [0, 2^32 - 1], triangle indices and counts in [0, 2^31 - 1].
Result<void> CheckIdsAndIndices(const far_lcm::step_reply_t& reply) {
  auto check = [](std::string_view field, const auto& values, int64_t max) -> Result<void> {
    for (size_t i = 0; i < values.size(); ++i) {
      if (values[i] < 0 || values[i] > max) {
        return BadReply(field, "[" + std::to_string(i) + "] = " + std::to_string(values[i]) +
                                   " is outside [0, " + std::to_string(max) + "]");
      }
    }
    return {};
  };
  for (const auto& [field, values] :
       {std::pair<const char*, const std::vector<int64_t>*>{"pcs_objects", &reply.pcs_objects},
        {"object_pair_a", &reply.object_pair_a},
        {"object_pair_b", &reply.object_pair_b},
        {"pcs_primitive_object", &reply.pcs_primitive_object},
        {"contact_object_a", &reply.contact_object_a},
        {"contact_object_b", &reply.contact_object_b},
        {"distance_object_a", &reply.distance_object_a},
        {"distance_object_b", &reply.distance_object_b},
        {"penetration_object_a", &reply.penetration_object_a},
        {"penetration_object_b", &reply.penetration_object_b}}) {
    if (auto ok = check(field, *values, int64_t{kMaxObjectId}); !ok) return ok.error();
  }
  for (const auto& [field, values] : {std::pair<const char*, const std::vector<int32_t>*>{
                                          "pcs_primitive_count", &reply.pcs_primitive_count},
                                      {"pcs_primitive_triangle", &reply.pcs_primitive_triangle},
                                      {"contact_triangle_a", &reply.contact_triangle_a},
                                      {"contact_triangle_b", &reply.contact_triangle_b},
                                      {"distance_triangle_a", &reply.distance_triangle_a},
                                      {"distance_triangle_b", &reply.distance_triangle_b}}) {
    if (auto ok = check(field, *values, int64_t{INT32_MAX}); !ok) return ok.error();
  }
  return {};
}

// Checks a reply's arrays: sizes equal to their counts, object ids in [0, 2^32 - 1], indices
// and counts >= 0, primitive counts that add up.
Result<void> CheckReplyArrays(const far_lcm::step_reply_t& reply) {
  if (!ArraysMatchTheirCounts(reply))
    return BadReply("num_*", "an array's size differs from its count");
  if (auto ok = CheckIdsAndIndices(reply); !ok) return ok;
  for (size_t i = 0; i < reply.stage_name.size(); ++i) {
    if (!ParseStage(reply.stage_name[i]))
      return BadReply("stage_name", "[" + std::to_string(i) + "] is no stage");
  }
  int64_t primitive_sum = 0;
  for (const int32_t count : reply.pcs_primitive_count) primitive_sum += count;
  if (primitive_sum != reply.num_pcs_primitives) {
    return BadReply("pcs_primitive_count", "counts add up to " + std::to_string(primitive_sum) +
                                               ", num_pcs_primitives is " +
                                               std::to_string(reply.num_pcs_primitives));
  }

  return CheckGeometryArrays(reply);
}

// The object PCS, pairs and primitive PCS of a checked reply.
Result<void> ReadCullingArrays(const far_lcm::step_reply_t& reply, StepResult& result) {
  for (const int64_t object : reply.pcs_objects)
    result.pcs_objects.push_back(static_cast<uint32_t>(object));
  for (int32_t i = 0; i < reply.num_object_pairs; ++i) {
    result.object_pairs.push_back({static_cast<uint32_t>(reply.object_pair_a[i]),
                                   static_cast<uint32_t>(reply.object_pair_b[i])});
  }
  size_t next = 0;
  for (int32_t i = 0; i < reply.num_pcs_primitive_objects; ++i) {
    const auto id = static_cast<uint32_t>(reply.pcs_primitive_object[i]);
    if (result.pcs_primitives.count(id) != 0) {
      return BadReply("pcs_primitive_object", "object " + std::to_string(id) + " appears twice");
    }
    auto& triangles = result.pcs_primitives[id];
    const auto count = static_cast<size_t>(reply.pcs_primitive_count[i]);
    triangles.assign(reply.pcs_primitive_triangle.begin() + static_cast<ptrdiff_t>(next),
                     reply.pcs_primitive_triangle.begin() + static_cast<ptrdiff_t>(next + count));
    next += count;
  }
  return {};
}

// The contact and distance pairs of a checked reply.
void ReadPairArrays(const far_lcm::step_reply_t& reply, StepResult& result) {
  result.contacts.reserve(static_cast<size_t>(reply.num_contacts));
  for (int32_t i = 0; i < reply.num_contacts; ++i) {
    result.contacts.push_back({static_cast<uint32_t>(reply.contact_object_a[i]),
                               static_cast<uint32_t>(reply.contact_triangle_a[i]),
                               static_cast<uint32_t>(reply.contact_object_b[i]),
                               static_cast<uint32_t>(reply.contact_triangle_b[i])});
  }
  result.distance_pairs.reserve(static_cast<size_t>(reply.num_distance_pairs));
  for (int32_t i = 0; i < reply.num_distance_pairs; ++i) {
    DistancePair pair;
    pair.pair = {static_cast<uint32_t>(reply.distance_object_a[i]),
                 static_cast<uint32_t>(reply.distance_triangle_a[i]),
                 static_cast<uint32_t>(reply.distance_object_b[i]),
                 static_cast<uint32_t>(reply.distance_triangle_b[i])};
    pair.distance = reply.distance[i];
    result.distance_pairs.push_back(pair);
  }
}

Eigen::Vector3d PointAt(const std::vector<double>& coords, size_t index) {
  return {coords[3 * index], coords[3 * index + 1], coords[3 * index + 2]};
}

// The contact geometry of a checked reply.
void ReadGeometryArrays(const far_lcm::step_reply_t& reply, StepResult& result) {
  size_t next_point = 0;
  result.contact_geometry.resize(static_cast<size_t>(reply.num_contact_geometry));
  for (size_t i = 0; i < result.contact_geometry.size(); ++i) {
    ContactGeometry& g = result.contact_geometry[i];
    g.num_points = reply.contact_point_count[i];
    for (int k = 0; k < g.num_points; ++k)
      g.points[k] = PointAt(reply.contact_points, next_point++);
    g.normal_a = PointAt(reply.contact_normal_a, i);
    g.normal_b = PointAt(reply.contact_normal_b, i);
    g.coplanar = reply.contact_coplanar[i];
  }
  result.closest_points.resize(static_cast<size_t>(reply.num_closest_point_coords / 3));
  for (size_t i = 0; i < result.closest_points.size(); ++i) {
    result.closest_points[i] = {PointAt(reply.closest_point_a, i),
                                PointAt(reply.closest_point_b, i)};
  }
  result.penetrations.resize(static_cast<size_t>(reply.num_penetrations));
  for (size_t i = 0; i < result.penetrations.size(); ++i) {
    Penetration& p = result.penetrations[i];
    p.object_a = static_cast<uint32_t>(reply.penetration_object_a[i]);
    p.object_b = static_cast<uint32_t>(reply.penetration_object_b[i]);
    p.closed = reply.penetration_closed[i];
    p.depth = reply.penetration_depth[i];
    p.direction = PointAt(reply.penetration_direction, i);
    p.point_a = PointAt(reply.penetration_point_a, i);
    p.point_b = PointAt(reply.penetration_point_b, i);
  }
}

void ReadStats(const far_lcm::step_reply_t& reply, StepResult& result) {
  result.stats.method = reply.method_run;
  result.stats.method_reason = reply.method_reason;
  StepStats& stats = result.stats;
  for (int32_t i = 0; i < reply.num_stages; ++i) {
    stats.stages.push_back({*ParseStage(reply.stage_name[i]), reply.stage_ms[i]});
  }
  stats.total_ms = reply.total_ms;
  stats.primitives_rendered = reply.primitives_rendered;
  stats.draws = reply.draws;
  stats.queries = reply.queries;
  stats.bytes_uploaded = reply.bytes_uploaded;
  stats.object_pairs = reply.object_pairs_considered;
  stats.pairs_considered = reply.pairs_considered;
  stats.pairs_tested = reply.pairs_tested;
  stats.object_radius = reply.object_radius;
  stats.primitive_radius = reply.primitive_radius;
  stats.certificate.guaranteed = reply.guaranteed;
  stats.certificate.basis = reply.guarantee_basis;
  for (int32_t i = 0; i < reply.num_levels; ++i) {
    LevelCertificate level;
    level.level = reply.level_name[i];
    level.views = reply.level_views[i];
    level.resolution = reply.level_resolution[i];
    level.offset_radius = reply.level_offset_radius[i];
    level.pixel_size = reply.level_pixel_size[i];
    level.depth_step = reply.level_depth_step[i];
    level.rounding = reply.level_rounding[i];
    level.world_min = {reply.level_world_min_x[i], reply.level_world_min_y[i],
                       reply.level_world_min_z[i]};
    level.world_max = {reply.level_world_max_x[i], reply.level_world_max_y[i],
                       reply.level_world_max_z[i]};
    stats.certificate.levels.push_back(std::move(level));
  }
}

}  // namespace

Result<StepResult> ParseStepReply(const far_lcm::step_reply_t& reply) {
  if (reply.reply_in_shm) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "step_reply_t.reply_in_shm: this is a stub; read the full reply from the "
                     "reply ring first (ReceiveStepReply)");
  }
  if (reply.status != kWireOk) {
    return MakeError(FromWireStatus(reply.status), reply.message);
  }
  if (auto ok = CheckReplyArrays(reply); !ok) return ok.error();
  StepResult result;
  if (auto ok = ReadCullingArrays(reply, result); !ok) return ok.error();
  ReadPairArrays(reply, result);
  ReadGeometryArrays(reply, result);
  ReadStats(reply, result);
  return result;
}

}  // namespace far::protocol
