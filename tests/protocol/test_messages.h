#pragma once

// Filled-in far_lcm messages for the protocol tests: every array and string non-empty, so a
// round trip exercises every field of every schema.

#include <cstring>

#include "far/protocol/message.h"
#include "far/protocol/version.h"

namespace far::protocol::testing {

inline void FillAuth(uint8_t (&auth)[32], uint8_t value) { std::memset(auth, value, 32); }

inline far_lcm::open_session_t SampleOpenSession() {
  far_lcm::open_session_t m{};
  m.protocol_version = kProtocolVersion;
  m.request_id = 11;
  m.client_name = "simulator-1";
  m.update_ring_bytes = 1 << 20;
  m.reply_ring_bytes = 0;
  return m;
}

inline far_lcm::open_session_reply_t SampleOpenSessionReply() {
  far_lcm::open_session_reply_t m{};
  m.protocol_version = kProtocolVersion;
  m.request_id = 11;
  m.status = 0;
  m.status_name = "ok";
  m.message = "fine";
  m.session_id = 3;
  m.shm_bytes = 4096 + (2 << 20);
  m.ring_layout_version = 1;
  m.update_ring_bytes = 1 << 20;
  m.reply_ring_bytes = 1 << 20;
  m.lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  m.request_channel = "FAR_S3_REQ";
  m.session_reply_channel = "FAR_S3_REPLY";
  m.max_objects = 1000;
  m.max_vertices_per_object = 1 << 22;
  m.max_triangles_per_object = 1 << 22;
  m.max_reply_pairs = 1 << 20;
  m.step_deadline_ms = 60000;
  return m;
}

inline far_lcm::sealed_t SampleSealed() {
  far_lcm::sealed_t m{};
  m.protocol_version = kProtocolVersion;
  m.session_id = 3;
  m.request_id = 12;
  std::memset(m.nonce, 7, sizeof(m.nonce));
  m.box_bytes = 20;
  m.box.assign(20, 0xab);
  return m;
}

inline far_lcm::step_status_t SampleStepStatus() {
  far_lcm::step_status_t m{};
  m.protocol_version = kProtocolVersion;
  m.session_id = 3;
  FillAuth(m.auth, 0);
  m.request_id = 7;
  m.step_id = 42;
  m.state = "stage";
  m.queue_position = 0;
  m.stage = "exact";
  m.elapsed_ms = 12.5;
  return m;
}

inline far_lcm::step_request_t SampleStepRequest() {
  far_lcm::step_request_t m{};
  m.protocol_version = kProtocolVersion;
  m.session_id = 3;
  FillAuth(m.auth, 0);
  m.request_id = 7;
  m.step_id = 42;
  m.ring_commit_sequence = 17;
  m.method = "far";
  m.mechanism = "id-buffer";
  m.output = "distance";
  m.depth_format = "depth24";
  m.resolution = 1024;
  m.subobject_size = 4;
  m.has_distance = true;
  m.distance = 0.25;
  m.geometry = true;
  m.timeout_ms = 30000;
  return m;
}

inline far_lcm::step_reply_t SampleStepReply() {
  far_lcm::step_reply_t m{};
  m.protocol_version = kProtocolVersion;
  m.session_id = 3;
  FillAuth(m.auth, 0);
  m.request_id = 7;
  m.step_id = 42;
  m.ring_applied_sequence = 17;
  m.status = 0;
  m.status_name = "ok";
  m.message = "";
  m.output = "distance";
  m.reply_in_shm = false;
  m.shm_reply_sequence = 0;
  m.shm_reply_index = 0;
  m.shm_reply_bytes = 0;
  FillAuth(m.shm_reply_hash, 0);
  m.num_pcs_objects = 3;
  m.pcs_objects = {1, 2, 5};
  m.num_object_pairs = 2;
  m.object_pair_a = {1, 2};
  m.object_pair_b = {2, 5};
  m.num_pcs_primitive_objects = 2;
  m.pcs_primitive_object = {1, 2};
  m.pcs_primitive_count = {2, 1};
  m.num_pcs_primitives = 3;
  m.pcs_primitive_triangle = {4, 9, 0};
  m.num_contacts = 1;
  m.contact_object_a = {1};
  m.contact_triangle_a = {4};
  m.contact_object_b = {2};
  m.contact_triangle_b = {0};
  m.num_distance_pairs = 2;
  m.distance_object_a = {1, 1};
  m.distance_triangle_a = {4, 9};
  m.distance_object_b = {2, 2};
  m.distance_triangle_b = {0, 0};
  m.distance = {0.0, 0.125};
  // Geometry for the contact (a segment), the distance pairs and one penetration.
  m.num_contact_geometry = m.num_contacts;
  m.contact_point_count = {2};
  m.contact_coplanar = {false};
  m.contact_points = {0.5, 0, 1, 1, 0, 1};
  m.num_contact_point_coords = 6;
  m.contact_normal_a = {0, 0, 1};
  m.contact_normal_b = {0, 0, -1};
  m.num_contact_normal_coords = 3;
  m.closest_point_a = {0, 0, 0, 1, 1, 1};
  m.closest_point_b = {0, 0, 0, 1, 1, 1.125};
  m.num_closest_point_coords = 6;
  m.num_penetrations = 1;
  m.penetration_object_a = {1};
  m.penetration_object_b = {2};
  m.penetration_closed = {true};
  m.penetration_depth = {0.25};
  m.penetration_direction = {0, 0, 1};
  m.penetration_point_a = {0, 0, 1};
  m.penetration_point_b = {0, 0, 0.75};
  m.num_penetration_coords = 3;
  m.num_stages = 2;
  m.stage_name = {"update", "object_cull"};
  m.stage_ms = {0.5, 1.25};
  m.total_ms = 1.75;
  m.primitives_rendered = 100;
  m.draws = 6;
  m.queries = 0;
  m.bytes_uploaded = 4096;
  m.object_pairs_considered = 2;
  m.pairs_considered = 3;
  m.pairs_tested = 3;
  m.object_radius = 0.01;
  m.primitive_radius = 0.001;
  m.guaranteed = true;
  m.guarantee_basis = "far: every level's offsets cover its pixel and depth steps";
  m.num_levels = 2;
  m.level_name = {"object", "sub-object"};
  m.level_views = {3, 3};
  m.level_resolution = {256, 1024};
  m.level_offset_radius = {0.02, 0.004};
  m.level_pixel_size = {0.01, 0.002};
  m.level_depth_step = {1e-6, 1e-6};
  m.level_rounding = {1e-7, 1e-7};
  m.level_world_min_x = {-1, -0.5};
  m.level_world_min_y = {-1, -0.5};
  m.level_world_min_z = {-1, -0.5};
  m.level_world_max_x = {1, 0.5};
  m.level_world_max_y = {1, 0.5};
  m.level_world_max_z = {1, 0.5};
  return m;
}

inline far_lcm::error_t SampleError() {
  far_lcm::error_t m{};
  m.protocol_version = kProtocolVersion;
  m.session_id = 3;
  FillAuth(m.auth, 0);
  m.request_id = 7;
  m.status = 1;
  m.status_name = "invalid_argument";
  m.message = "step_request_t.resolution: 5 is outside [8, 8192]";
  m.session_closed = false;
  return m;
}

inline far_lcm::status_request_t SampleStatusRequest() {
  far_lcm::status_request_t m{};
  m.protocol_version = kProtocolVersion;
  m.request_id = 1;
  return m;
}

inline far_lcm::status_reply_t SampleStatusReply() {
  far_lcm::status_reply_t m{};
  m.protocol_version = kProtocolVersion;
  m.request_id = 1;
  m.daemon_version = "0.1.0";
  m.daemon_name = "far";
  m.gl_renderer = "llvmpipe";
  m.gl_device = "surfaceless";
  m.lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  m.channel_prefix = "FAR_";
  m.uptime_ms = 1000;
  m.max_sessions = 16;
  m.max_sessions_per_user = 4;
  m.sessions_open = 3;
  m.steps_total = 5;
  m.errors_total = 1;
  m.rejected_messages_total = 2;
  m.latency_p50_ms = 1.5;
  m.latency_p90_ms = 2.5;
  m.latency_p99_ms = 4.0;
  m.latency_max_ms = 9.0;
  m.latency_samples = 5;
  m.num_sessions = 2;
  m.session_id = {3, 4};
  m.session_uid = {1000, 1000};
  m.session_client_name = {"a", "bb"};
  m.session_steps = {5, 0};
  m.session_objects = {10, 0};
  m.session_triangles = {1200, 0};
  m.session_latency_p50_ms = {1.5, 0.0};
  m.session_latency_p99_ms = {4.0, 0.0};
  m.num_error_kinds = 2;
  m.error_kind = {"busy", "invalid_argument"};
  m.error_count = {1, 3};
  m.daemon_pid = 4321;
  m.opens_refused_total = 2;
  m.memory_rss_bytes = 64 << 20;
  m.segment_bytes = 32 << 20;
  m.num_gpu_names = 3;
  m.gpu_name = {"1", "GPU-6f0e2b1c-0000-4000-8000-000000000001", "0000:3b:00.0"};
  m.num_methods = 2;
  m.method_name = {"bvh", "gpu"};
  m.method_steps = {3, 2};
  m.session_pid = {777, 778};
  return m;
}

inline far_lcm::recording_header_t SampleRecordingHeader() {
  far_lcm::recording_header_t m{};
  m.protocol_version = kProtocolVersion;
  m.format_version = 1;
  m.far_version = "0.1.0";
  m.client_name = "sim";
  m.daemon_name = "far";
  m.gl_renderer = "llvmpipe (LLVM 15.0.6, 256 bits)";
  m.session_id = 12;
  m.start_time_us = 1700000000000000;
  return m;
}

inline far_lcm::ring_record_t SampleRingRecord() {
  far_lcm::ring_record_t m{};
  m.protocol_version = kProtocolVersion;
  m.sequence = 1;
  m.step_id = 0;
  m.type = 1;
  m.object_id = 4;
  m.motion = 1;
  m.X_WO[3] = 1;
  m.num_coordinates = 9;
  m.p_MV = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  m.num_indices = 3;
  m.triangles = {0, 1, 2};
  return m;
}

}  // namespace far::protocol::testing
