// Meaning checks of client messages and channel names: every field's range, with the field and
// the value named in the message.

#include "far/protocol/message_validate.h"

#include <cmath>
#include <limits>

#include "test_messages.h"
#include <gtest/gtest.h>

#include "far/protocol/channels.h"

namespace far::protocol {
namespace {

using testing::SampleOpenSession;
using testing::SampleStepRequest;

void ExpectInvalid(const far_lcm::step_request_t& message, const std::string& substring) {
  auto command = ValidateStepRequest(message);
  ASSERT_FALSE(command) << "accepted; expected " << substring;
  EXPECT_EQ(command.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(command.error().message.find(substring), std::string::npos) << command.error().message;
}

void ExpectInvalid(const far_lcm::open_session_t& message, const std::string& substring) {
  auto params = ValidateOpenSession(message);
  ASSERT_FALSE(params) << "accepted; expected " << substring;
  EXPECT_EQ(params.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(params.error().message.find(substring), std::string::npos) << params.error().message;
}

TEST(ValidateStepRequestTest, ConvertsAValidRequest) {
  auto command = ValidateStepRequest(SampleStepRequest());
  ASSERT_TRUE(command) << command.error().message;
  EXPECT_EQ(command->session_id, 3);
  EXPECT_EQ(command->request_id, 7);
  EXPECT_EQ(command->step_id, 42);
  EXPECT_EQ(command->ring_commit_sequence, 17u);
  EXPECT_EQ(command->request.method, Method::kFar);
  EXPECT_EQ(command->request.mechanism, QueryMechanism::kIdBuffer);
  EXPECT_EQ(command->request.output, Output::kDistancePairs);
  EXPECT_EQ(command->request.depth_format, DepthFormat::kDepth24);
  EXPECT_EQ(command->request.resolution, 1024);
  EXPECT_EQ(command->request.subobject_size, 4);
  ASSERT_TRUE(command->request.distance);
  EXPECT_EQ(*command->request.distance, 0.25);
}

TEST(ValidateStepRequestTest, ChecksIds) {
  auto m = SampleStepRequest();
  m.session_id = 0;
  ExpectInvalid(m, "step_request_t.session_id: 0 is not > 0");
  m = SampleStepRequest();
  m.request_id = -1;
  ExpectInvalid(m, "step_request_t.request_id: -1 is negative");
  m = SampleStepRequest();
  m.step_id = -5;
  ExpectInvalid(m, "step_request_t.step_id: -5 is negative");
  m = SampleStepRequest();
  m.ring_commit_sequence = -1;
  ExpectInvalid(m, "step_request_t.ring_commit_sequence: -1 is negative");
}

TEST(ValidateStepRequestTest, ChecksNames) {
  auto m = SampleStepRequest();
  m.method = "FAR";
  ExpectInvalid(m,
                "step_request_t.method: 'FAR' is not one of auto, aabb, bvh, gpu, cullide, far, "
                "far-exact-offset, fcl, exact");
  // No method named: the default, auto.
  m = SampleStepRequest();
  m.method = "";
  auto command = ValidateStepRequest(m);
  ASSERT_TRUE(command) << command.error().message;
  EXPECT_EQ(command->request.method, Method::kAuto);
  m = SampleStepRequest();
  m.mechanism = "queries";
  ExpectInvalid(m, "step_request_t.mechanism: 'queries' is not one of occlusion-query, id-buffer");
  m = SampleStepRequest();
  m.output = "";
  ExpectInvalid(m, "step_request_t.output: '' is not one of object-pcs, pairs, pcs, contacts");
  m = SampleStepRequest();
  m.depth_format = "depth8";
  ExpectInvalid(m, "step_request_t.depth_format: 'depth8' is not one of depth16, depth24");
}

TEST(ValidateStepRequestTest, EscapesClientTextInMessages) {
  auto m = SampleStepRequest();
  m.method = "far\nFAKE LOG LINE";
  ExpectInvalid(m, "'far\\x0aFAKE LOG LINE'");
  m.method = std::string(500, 'x');
  ExpectInvalid(m, std::string(64, 'x') + "...'");
}

TEST(ValidateStepRequestTest, ChecksResolutionRange) {
  auto m = SampleStepRequest();
  m.resolution = 5;
  ExpectInvalid(m, "step_request_t.resolution: 5 is outside [8, 8192]");
  m.resolution = 8193;
  ExpectInvalid(m, "step_request_t.resolution: 8193 is outside [8, 8192]");
  m.resolution = -2147483647 - 1;
  ExpectInvalid(m, "step_request_t.resolution: -2147483648 is outside");
  m.resolution = 8;
  EXPECT_TRUE(ValidateStepRequest(m));
  m.resolution = 8192;
  EXPECT_TRUE(ValidateStepRequest(m));
}

TEST(ValidateStepRequestTest, ChecksSubobjectSizeRange) {
  auto m = SampleStepRequest();
  m.subobject_size = 0;
  ExpectInvalid(m, "step_request_t.subobject_size: 0 is outside [1, 1048576]");
  m.subobject_size = (1 << 20) + 1;
  ExpectInvalid(m, "step_request_t.subobject_size: 1048577 is outside [1, 1048576]");
}

TEST(ValidateStepRequestTest, ChecksDistance) {
  auto m = SampleStepRequest();
  m.distance = std::numeric_limits<double>::quiet_NaN();
  ExpectInvalid(m, "step_request_t.distance: nan is not a finite number in [0, 1e+12]");
  m.distance = std::numeric_limits<double>::infinity();
  ExpectInvalid(m, "step_request_t.distance: inf is not a finite number");
  m.distance = -0.5;
  ExpectInvalid(m, "step_request_t.distance: -0.5 is not a finite number");
  m.distance = 1e13;
  ExpectInvalid(m, "step_request_t.distance: 1e+13 is not a finite number");
  m = SampleStepRequest();
  m.output = "contacts";
  m.has_distance = false;
  ExpectInvalid(m, "step_request_t.distance: 0.25 is set but has_distance is false");
  m.distance = 0;
  EXPECT_TRUE(ValidateStepRequest(m));
}

TEST(ValidateStepRequestTest, ChecksCombinations) {
  auto m = SampleStepRequest();
  m.has_distance = false;
  m.distance = 0;
  ExpectInvalid(m, "step_request_t.output: 'distance' needs a distance D");
  m = SampleStepRequest();
  m.method = "fcl";
  ExpectInvalid(m, "step_request_t.method: 'fcl' answers contacts only");
}

TEST(ValidateOpenSessionTest, AcceptsAValidRequest) {
  auto params = ValidateOpenSession(SampleOpenSession());
  ASSERT_TRUE(params) << params.error().message;
  EXPECT_EQ(params->client_name, "simulator-1");
  EXPECT_EQ(params->update_ring_bytes, 1u << 20);
  EXPECT_EQ(params->reply_ring_bytes, 0u);
}

TEST(ValidateOpenSessionTest, ChecksEveryField) {
  auto m = SampleOpenSession();
  m.client_name = "";
  ExpectInvalid(m, "open_session_t.client_name: length 0 is outside [1, 64]");
  m.client_name = std::string(65, 'a');
  ExpectInvalid(m, "open_session_t.client_name: length 65 is outside [1, 64]");
  m.client_name = "tab\there";
  ExpectInvalid(m,
                "open_session_t.client_name: 'tab\\x09here' has a character that is not "
                "printable ASCII");
  m = SampleOpenSession();
  m.update_ring_bytes = 100000;
  ExpectInvalid(m,
                "open_session_t.update_ring_bytes: 100000 is not 0 or a power of two in "
                "[65536, 1073741824]");
  m.update_ring_bytes = -65536;
  ExpectInvalid(m, "open_session_t.update_ring_bytes: -65536");
  m = SampleOpenSession();
  m.reply_ring_bytes = int64_t{1} << 31;
  ExpectInvalid(m, "open_session_t.reply_ring_bytes: 2147483648");
}

TEST(ValidateSessionIdsTest, NamesTheMessageType) {
  auto ok = ValidateSessionIds(MessageType::kStepStatus, -3, 0);
  ASSERT_FALSE(ok);
  EXPECT_NE(ok.error().message.find("step_status_t.session_id: -3 is not > 0"), std::string::npos);
  EXPECT_TRUE(ValidateSessionIds(MessageType::kStepRequest, 1, 0));
}

TEST(ValidateStepRequestTest, CarriesTheClientsTimeout) {
  auto command = ValidateStepRequest(SampleStepRequest());
  ASSERT_TRUE(command) << command.error().message;
  EXPECT_EQ(command->timeout_ms, 30000);
  auto m = SampleStepRequest();
  m.timeout_ms = -1;
  ExpectInvalid(m, "step_request_t.timeout_ms: -1 is negative");
}

TEST(ChannelsTest, NamesSessionChannelsWithTheDaemonsPrefix) {
  EXPECT_EQ(ChannelPrefix("far"), "FAR_");
  EXPECT_EQ(ChannelPrefix("gpu-1"), "FAR_GPU_1_");
  EXPECT_EQ(SessionRequestChannel("FAR_", 12), "FAR_S12_REQ");
  EXPECT_EQ(SessionReplyChannel("FAR_GPU_1_", 12), "FAR_GPU_1_S12_REPLY");
  EXPECT_EQ(SessionRequestChannelPattern("FAR_GPU_1_"), "FAR_GPU_1_S[0-9]+_REQ");
  EXPECT_EQ(ParseSessionRequestChannel("FAR_", "FAR_S12_REQ"), 12);
  EXPECT_EQ(ParseSessionRequestChannel("FAR_", "FAR_S999999999999999999_REQ"), 999999999999999999);
  EXPECT_FALSE(ParseSessionRequestChannel("FAR_", "FAR_S9999999999999999999_REQ"));  // 19 digits
  EXPECT_FALSE(ParseSessionRequestChannel("FAR_", "FAR_S012_REQ"));
  EXPECT_FALSE(ParseSessionRequestChannel("FAR_", "FAR_S_REQ"));
  EXPECT_FALSE(ParseSessionRequestChannel("FAR_", "FAR_S1x_REQ"));
  EXPECT_FALSE(ParseSessionRequestChannel("FAR_", "FAR_S12_REPLY"));
  EXPECT_FALSE(ParseSessionRequestChannel("FAR_", ""));
  // Another daemon's channels are not this one's.
  EXPECT_FALSE(ParseSessionRequestChannel("FAR_", "FAR_GPU_1_S12_REQ"));
  EXPECT_EQ(ParseSessionRequestChannel("FAR_GPU_1_", "FAR_GPU_1_S12_REQ"), 12);
  EXPECT_FALSE(ParseSessionRequestChannel("FAR_GPU_1_", "FAR_S12_REQ"));
}

TEST(ChannelsTest, DaemonNamesAreShortLowerCaseWords) {
  EXPECT_TRUE(IsValidDaemonName("far"));
  EXPECT_TRUE(IsValidDaemonName("gpu-1"));
  EXPECT_TRUE(IsValidDaemonName("a234567890123456"));
  EXPECT_FALSE(IsValidDaemonName(""));
  EXPECT_FALSE(IsValidDaemonName("1gpu"));
  EXPECT_FALSE(IsValidDaemonName("GPU"));
  EXPECT_FALSE(IsValidDaemonName("a2345678901234567"));
  EXPECT_FALSE(IsValidDaemonName("../x"));
  EXPECT_FALSE(IsValidDaemonName("a b"));
}

}  // namespace
}  // namespace far::protocol
