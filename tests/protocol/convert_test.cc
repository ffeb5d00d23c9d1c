// Conversions between far's step types and the wire messages.

#include "far/protocol/convert.h"

#include <cmath>

#include "test_messages.h"
#include <gtest/gtest.h>

#include "far/protocol/message_validate.h"

namespace far::protocol {
namespace {

StepResult SampleResult() {
  StepResult result;
  result.pcs_objects = {1, 2, 7};
  result.object_pairs = {{1, 2}, {2, 7}};
  result.pcs_primitives[1] = {0, 5, 9};
  result.pcs_primitives[7] = {3};
  result.contacts = {{1, 0, 2, 4}, {2, 8, 7, 3}};
  result.distance_pairs = {{{1, 5, 2, 1}, 0.5}, {{2, 2, 7, 0}, 1e-9}};
  result.stats.stages = {{Stage::kUpdate, 0.1}, {Stage::kObjectCull, 2.5}, {Stage::kExact, 7}};
  result.stats.total_ms = 9.6;
  result.stats.primitives_rendered = 1234;
  result.stats.draws = 12;
  result.stats.queries = 0;
  result.stats.bytes_uploaded = 1 << 20;
  result.stats.object_pairs = 2;
  result.stats.pairs_considered = 40;
  result.stats.pairs_tested = 30;
  result.stats.object_radius = 0.01;
  result.stats.primitive_radius = 0.002;
  return result;
}

TEST(ConvertTest, WireStatusCodesArePinned) {
  EXPECT_EQ(ToWireStatus(ErrorCode::kInvalidArgument), 1);
  EXPECT_EQ(ToWireStatus(ErrorCode::kParseError), 2);
  EXPECT_EQ(ToWireStatus(ErrorCode::kIoError), 3);
  EXPECT_EQ(ToWireStatus(ErrorCode::kNotFound), 4);
  EXPECT_EQ(ToWireStatus(ErrorCode::kLimitExceeded), 5);
  EXPECT_EQ(ToWireStatus(ErrorCode::kUnavailable), 6);
  EXPECT_EQ(ToWireStatus(ErrorCode::kBusy), 7);
  EXPECT_EQ(ToWireStatus(ErrorCode::kPermissionDenied), 8);
  EXPECT_EQ(ToWireStatus(ErrorCode::kTimeout), 9);
  EXPECT_EQ(ToWireStatus(ErrorCode::kVersionMismatch), 10);
  EXPECT_EQ(ToWireStatus(ErrorCode::kInternal), 11);
  for (int code = 0; code <= static_cast<int>(ErrorCode::kInternal); ++code) {
    EXPECT_EQ(FromWireStatus(ToWireStatus(static_cast<ErrorCode>(code))),
              static_cast<ErrorCode>(code));
  }
  EXPECT_EQ(FromWireStatus(0), ErrorCode::kInternal);
  EXPECT_EQ(FromWireStatus(12), ErrorCode::kInternal);
  EXPECT_EQ(FromWireStatus(-1), ErrorCode::kInternal);
}

TEST(ConvertTest, StepRequestRoundTripsThroughValidation) {
  StepRequest request;
  request.method = Method::kFarExactOffset;
  request.mechanism = QueryMechanism::kOcclusionQuery;
  request.resolution = 512;
  request.depth_format = DepthFormat::kDepth32F;
  request.subobject_size = 8;
  request.distance = 0.125;
  request.output = Output::kDistancePairs;
  request.geometry = true;
  const auto message = MakeStepRequest(4, 9, 100, 55, request);
  auto bytes = EncodeMessage(message);
  ASSERT_TRUE(bytes);
  auto decoded =
      DecodeMessage<far_lcm::step_request_t>(bytes->data(), bytes->size(), kMaxControlMessageBytes);
  ASSERT_TRUE(decoded) << decoded.error().message;
  auto command = ValidateStepRequest(*decoded);
  ASSERT_TRUE(command) << command.error().message;
  EXPECT_EQ(command->session_id, 4);
  EXPECT_EQ(command->request_id, 9);
  EXPECT_EQ(command->step_id, 100);
  EXPECT_EQ(command->ring_commit_sequence, 55u);
  EXPECT_EQ(command->request.method, request.method);
  EXPECT_EQ(command->request.mechanism, request.mechanism);
  EXPECT_EQ(command->request.resolution, request.resolution);
  EXPECT_EQ(command->request.depth_format, request.depth_format);
  EXPECT_EQ(command->request.subobject_size, request.subobject_size);
  EXPECT_EQ(command->request.distance, request.distance);
  EXPECT_EQ(command->request.output, request.output);
  EXPECT_TRUE(command->request.geometry);
}

TEST(ConvertTest, StepResultRoundTripsThroughTheWire) {
  const StepResult result = SampleResult();
  auto reply = MakeStepReply({4, 9, 100, 55}, Output::kDistancePairs, result);
  ASSERT_TRUE(reply) << reply.error().message;
  auto bytes = EncodeMessage(*reply);
  ASSERT_TRUE(bytes);
  auto decoded =
      DecodeMessage<far_lcm::step_reply_t>(bytes->data(), bytes->size(), kMaxStepReplyBytes);
  ASSERT_TRUE(decoded) << decoded.error().message;
  EXPECT_EQ(decoded->output, "distance");
  EXPECT_EQ(decoded->ring_applied_sequence, 55);
  auto parsed = ParseStepReply(*decoded);
  ASSERT_TRUE(parsed) << parsed.error().message;
  EXPECT_EQ(parsed->pcs_objects, result.pcs_objects);
  EXPECT_EQ(parsed->object_pairs, result.object_pairs);
  EXPECT_EQ(parsed->pcs_primitives, result.pcs_primitives);
  EXPECT_EQ(parsed->contacts, result.contacts);
  ASSERT_EQ(parsed->distance_pairs.size(), result.distance_pairs.size());
  for (size_t i = 0; i < result.distance_pairs.size(); ++i) {
    EXPECT_EQ(parsed->distance_pairs[i].pair, result.distance_pairs[i].pair);
    EXPECT_EQ(parsed->distance_pairs[i].distance, result.distance_pairs[i].distance);
  }
  ASSERT_EQ(parsed->stats.stages.size(), 3u);
  EXPECT_EQ(parsed->stats.stages[1].stage, Stage::kObjectCull);
  EXPECT_EQ(parsed->stats.stages[1].ms, 2.5);
  EXPECT_EQ(parsed->stats.total_ms, 9.6);
  EXPECT_EQ(parsed->stats.primitives_rendered, 1234);
  EXPECT_EQ(parsed->stats.bytes_uploaded, 1 << 20);
  EXPECT_EQ(parsed->stats.pairs_tested, 30);
  EXPECT_EQ(parsed->stats.primitive_radius, 0.002);
}

TEST(ConvertTest, ErrorRepliesCarryCodeAndMessage) {
  const Error error = MakeError(ErrorCode::kLimitExceeded, "update ring: record 3: too big");
  const auto reply = MakeStepErrorReply({4, 9, 100, 2}, error);
  EXPECT_EQ(reply.status, 5);
  EXPECT_EQ(reply.status_name, "limit_exceeded");
  auto bytes = EncodeMessage(reply);
  ASSERT_TRUE(bytes);
  auto decoded =
      DecodeMessage<far_lcm::step_reply_t>(bytes->data(), bytes->size(), kMaxStepReplyBytes);
  ASSERT_TRUE(decoded);
  auto parsed = ParseStepReply(*decoded);
  ASSERT_FALSE(parsed);
  EXPECT_EQ(parsed.error().code, ErrorCode::kLimitExceeded);
  EXPECT_EQ(parsed.error().message, error.message);

  const auto message = MakeErrorMessage(4, -1, error, true);
  EXPECT_EQ(message.status, 5);
  EXPECT_TRUE(message.session_closed);
  EXPECT_EQ(message.message, error.message);
}

TEST(ConvertTest, ParseStepReplyRejectsInconsistentReplies) {
  auto reply = testing::SampleStepReply();
  reply.contact_triangle_b = {-4};
  auto parsed = ParseStepReply(reply);
  ASSERT_FALSE(parsed);
  EXPECT_NE(parsed.error().message.find(
                "step_reply_t.contact_triangle_b: [0] = -4 is outside [0, 2147483647]"),
            std::string::npos);

  reply = testing::SampleStepReply();
  reply.pcs_primitive_count = {2, 2};
  parsed = ParseStepReply(reply);
  ASSERT_FALSE(parsed);
  EXPECT_NE(parsed.error().message.find("counts add up to 4, num_pcs_primitives is 3"),
            std::string::npos);

  reply = testing::SampleStepReply();
  reply.stage_name[1] = "object_cul";  // a stage far has not
  parsed = ParseStepReply(reply);
  ASSERT_FALSE(parsed);
  EXPECT_NE(parsed.error().message.find("stage_name: [1] is no stage"), std::string::npos)
      << parsed.error().message;

  reply = testing::SampleStepReply();
  reply.num_contacts = 5;  // a hand-built message whose arrays do not match
  parsed = ParseStepReply(reply);
  ASSERT_FALSE(parsed);
  EXPECT_EQ(parsed.error().code, ErrorCode::kParseError);

  reply = testing::SampleStepReply();
  reply.reply_in_shm = true;
  parsed = ParseStepReply(reply);
  ASSERT_FALSE(parsed);
  EXPECT_EQ(parsed.error().code, ErrorCode::kInvalidArgument);
}

TEST(ConvertTest, ContactGeometryRoundTripsThroughTheWire) {
  StepResult result = SampleResult();
  ContactGeometry point;
  point.num_points = 1;
  point.points[0] = {1, 2, 3};
  point.normal_a = {0, 0, 1};
  ContactGeometry hexagon;
  hexagon.num_points = 6;
  for (int k = 0; k < 6; ++k) hexagon.points[k] = {std::cos(k), std::sin(k), 0.1 * k};
  hexagon.normal_a = {0, 1, 0};
  hexagon.normal_b = {0, -1, 0};
  hexagon.coplanar = true;
  result.contact_geometry = {point, hexagon};
  result.closest_points = {{{0, 0, 0}, {0, 0, 0.5}}, {{1, 1, 1}, {1, 1, 1 + 1e-9}}};
  Penetration closed{1, 2, true, 0.25, {0, 0, 1}, {0, 0, 1}, {0, 0, 0.75}};
  Penetration open;  // not closed: zeros
  open.object_a = 2;
  open.object_b = 7;
  result.penetrations = {closed, open};
  auto reply = MakeStepReply({4, 9, 100, 55}, Output::kDistancePairs, result);
  ASSERT_TRUE(reply) << reply.error().message;
  auto bytes = EncodeMessage(*reply);
  ASSERT_TRUE(bytes);
  auto decoded =
      DecodeMessage<far_lcm::step_reply_t>(bytes->data(), bytes->size(), kMaxStepReplyBytes);
  ASSERT_TRUE(decoded) << decoded.error().message;
  auto parsed = ParseStepReply(*decoded);
  ASSERT_TRUE(parsed) << parsed.error().message;
  ASSERT_EQ(parsed->contact_geometry.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const ContactGeometry& a = result.contact_geometry[i];
    const ContactGeometry& b = parsed->contact_geometry[i];
    ASSERT_EQ(a.num_points, b.num_points);
    for (int k = 0; k < a.num_points; ++k) EXPECT_EQ(a.points[k], b.points[k]);
    EXPECT_EQ(a.normal_a, b.normal_a);
    EXPECT_EQ(a.normal_b, b.normal_b);
    EXPECT_EQ(a.coplanar, b.coplanar);
  }
  ASSERT_EQ(parsed->closest_points.size(), 2u);
  EXPECT_EQ(parsed->closest_points[1].point_b, result.closest_points[1].point_b);
  ASSERT_EQ(parsed->penetrations.size(), 2u);
  EXPECT_EQ(parsed->penetrations[0].depth, 0.25);
  EXPECT_EQ(parsed->penetrations[0].point_b, closed.point_b);
  EXPECT_EQ(parsed->penetrations[1].object_b, 7u);
  EXPECT_FALSE(parsed->penetrations[1].closed);

  // Without geometry nothing is sent.
  result = SampleResult();
  reply = MakeStepReply({4, 9, 100, 55}, Output::kDistancePairs, result);
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->num_contact_geometry, 0);
  EXPECT_EQ(reply->num_closest_point_coords, 0);
  EXPECT_EQ(reply->num_penetrations, 0);
}

TEST(ConvertTest, ParseStepReplyRejectsInconsistentGeometry) {
  auto reply = testing::SampleStepReply();
  ASSERT_TRUE(ParseStepReply(reply)) << "the sample is consistent";
  reply.contact_point_count = {7};
  auto parsed = ParseStepReply(reply);
  ASSERT_FALSE(parsed);
  EXPECT_NE(parsed.error().message.find("contact_point_count: [0] = 7 is outside [1, 6]"),
            std::string::npos)
      << parsed.error().message;

  reply = testing::SampleStepReply();
  reply.contact_point_count = {1};  // the points say 2
  parsed = ParseStepReply(reply);
  ASSERT_FALSE(parsed);
  EXPECT_EQ(parsed.error().code, ErrorCode::kParseError);

  reply = testing::SampleStepReply();
  reply.num_closest_point_coords = 3;
  reply.closest_point_a.resize(3);
  reply.closest_point_b.resize(3);
  parsed = ParseStepReply(reply);
  ASSERT_FALSE(parsed);
  EXPECT_NE(parsed.error().message.find("num_closest_point_coords"), std::string::npos);

  reply = testing::SampleStepReply();
  reply.penetration_object_b = {int64_t{1} << 40};
  parsed = ParseStepReply(reply);
  ASSERT_FALSE(parsed);
  EXPECT_NE(parsed.error().message.find("penetration_object_b"), std::string::npos);
}

TEST(ConvertTest, EveryUint32IdRoundTrips) {
  StepResult result;
  result.pcs_objects = {0, 0x80000000u, 0xFFFFFFFFu};
  result.contacts = {{0, 1, 0xFFFFFFFFu, 2}};
  auto reply = MakeStepReply({1, 1, 1, 0}, Output::kContacts, result);
  ASSERT_TRUE(reply) << reply.error().message;
  auto parsed = ParseStepReply(*reply);
  ASSERT_TRUE(parsed) << parsed.error().message;
  EXPECT_EQ(parsed->pcs_objects, result.pcs_objects);
  EXPECT_EQ(parsed->contacts, result.contacts);
}

TEST(ConvertTest, MakeStepReplyRejectsTriangleIndicesThatDoNotFitTheWire) {
  StepResult result;
  result.contacts = {{1, 0x80000000u, 2, 0}};
  auto reply = MakeStepReply({1, 1, 1, 0}, Output::kContacts, result);
  ASSERT_FALSE(reply);
  EXPECT_EQ(reply.error().code, ErrorCode::kInternal);
}

TEST(ConvertTest, ParseStepReplyRejectsIdsBeyondUint32) {
  StepResult result;
  result.pcs_objects = {7};
  auto reply = MakeStepReply({1, 1, 1, 0}, Output::kObjectPcs, result);
  ASSERT_TRUE(reply);
  reply->pcs_objects[0] = int64_t{1} << 32;
  auto parsed = ParseStepReply(*reply);
  ASSERT_FALSE(parsed);
  EXPECT_NE(parsed.error().message.find("step_reply_t.pcs_objects: [0] = 4294967296 is outside"),
            std::string::npos)
      << parsed.error().message;
}

}  // namespace
}  // namespace far::protocol
