// far recordings read as untrusted input: IndexRecording and ParseRingRecord accept what the
// recorder writes and refuse, with an error naming the event, everything else.

#include "far/protocol/recording.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "test_messages.h"
#include <gtest/gtest.h>

#include "far/protocol/convert.h"

namespace far::protocol {
namespace {

namespace wire = far_lcm;

Mesh Triangle() {
  Mesh mesh;
  mesh.p_MV = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 2}};
  return mesh;
}

Pose SomePose() {
  Pose pose;
  pose.translation = {0.1, -2.5, 3};
  pose.rotation = Eigen::Quaterniond(0.5, 0.5, 0.5, 0.5);
  return pose;
}

// A step request for step `step_id` that commits `commit`.
wire::step_request_t Request(int64_t step_id, uint64_t commit) {
  StepRequest request;
  request.method = Method::kBvh;
  return MakeStepRequest(5, step_id + 1, step_id, commit, request, 1000);
}

wire::step_reply_t Reply(int64_t step_id) {
  StepResult result;
  result.contacts = {{1, 0, 2, 0}};
  result.stats.method = "bvh";
  auto reply = MakeStepReply({5, step_id + 1, step_id, 0}, Output::kContacts, result);
  EXPECT_TRUE(reply);
  return *reply;
}

class RecordingTest : public ::testing::Test {
 public:  // the cases below write through a RecordingTest&
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("far-recording-test-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
    path_ = (dir_ / "r.farrec").string();
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // A new file with the events added by Add, in order.
  void Begin() {
    const int fd = open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    ASSERT_GE(fd, 0);
    auto writer = LcmLogWriter::FromDescriptor(fd, path_);
    ASSERT_TRUE(writer);
    log_ = std::move(*writer);
  }
  template <typename T>
  void Add(std::string_view channel, const T& message) {
    auto bytes = EncodeMessage(message);
    ASSERT_TRUE(bytes);
    ASSERT_TRUE(log_->Write(channel, *bytes, 0));
  }
  void AddBytes(std::string_view channel, const std::vector<uint8_t>& bytes) {
    ASSERT_TRUE(log_->Write(channel, bytes, 0));
  }
  Result<RecordingIndex> End() {
    EXPECT_TRUE(log_->Flush());
    log_.reset();
    auto reader = OpenRecording(path_);
    if (!reader) return reader.error();
    return IndexRecording(**reader);
  }

  // header; two records; step 0 commits them; its reply; a pose; step 1; its reply.
  void WriteGoodRecording() {
    Begin();
    Add(kRecordingHeaderChannel, testing::SampleRecordingHeader());
    Add(kRecordingRingChannel,
        MakeAddObjectRingRecord(1, 0, 1, Triangle(), Motion::kStatic, SomePose()));
    Add(kRecordingRingChannel,
        MakeAddObjectRingRecord(2, 0, 2, Triangle(), Motion::kRigid, SomePose()));
    Add(kRecordingRequestChannel, Request(0, 2));
    Add(kRecordingReplyChannel, Reply(0));
    Add(kRecordingRingChannel, MakeSetPoseRingRecord(3, 1, 2, SomePose()));
    Add(kRecordingRequestChannel, Request(1, 3));
    Add(kRecordingRingChannel, MakeRemoveObjectRingRecord(4, 2, 1));
    Add(kRecordingReplyChannel, Reply(1));
  }

  void ExpectRefused(ErrorCode code, const std::string& says) {
    auto index = End();
    ASSERT_FALSE(index) << "accepted; expected: " << says;
    EXPECT_EQ(index.error().code, code) << index.error().message;
    EXPECT_NE(index.error().message.find(says), std::string::npos) << index.error().message;
  }

  std::filesystem::path dir_;
  std::string path_;
  std::unique_ptr<LcmLogWriter> log_;
};

TEST_F(RecordingTest, AGoodRecordingIndexesIntoStepsWithTheirRecordsAndReplies) {
  WriteGoodRecording();
  auto index = End();
  ASSERT_TRUE(index) << index.error().message;
  EXPECT_EQ(index->events, 9);
  EXPECT_EQ(index->header.client_name, "sim");
  EXPECT_EQ(index->ring_records, 4u);
  EXPECT_EQ(index->uncommitted_records, 1u);
  ASSERT_EQ(index->steps.size(), 2u);
  EXPECT_EQ(index->steps[0].ring_record_offsets.size(), 2u);
  EXPECT_EQ(index->steps[1].ring_record_offsets.size(), 1u);
  EXPECT_EQ(index->steps[1].command.request.method, Method::kBvh);
  ASSERT_TRUE(index->steps[1].reply_offset);

  auto reader = OpenRecording(path_);
  ASSERT_TRUE(reader);
  auto pose = ReadRecordedUpdate(**reader, index->steps[1].ring_record_offsets[0]);
  ASSERT_TRUE(pose) << pose.error().message;
  ASSERT_TRUE(std::holds_alternative<far::SetPose>(pose->update));
  const Pose& read = std::get<far::SetPose>(pose->update).X_WO;
  EXPECT_EQ(read.translation, SomePose().translation);
  EXPECT_EQ(read.rotation.coeffs(), SomePose().rotation.coeffs());  // bit for bit
  auto reply = ReadRecordedReply(**reader, *index->steps[0].reply_offset);
  ASSERT_TRUE(reply) << reply.error().message;
  ASSERT_TRUE(reply->result);
  EXPECT_EQ(reply->result->contacts.size(), 1u);
  // An offset that is not a reply's is refused.
  EXPECT_FALSE(ReadRecordedReply(**reader, index->steps[1].ring_record_offsets[0]));
  EXPECT_FALSE(ReadRecordedReply(**reader, 3));
}

TEST_F(RecordingTest, ARecordedFailedStepIsAResultNotABadRecording) {
  Begin();
  Add(kRecordingHeaderChannel, testing::SampleRecordingHeader());
  Add(kRecordingRequestChannel, Request(0, 0));
  Add(kRecordingReplyChannel,
      MakeStepErrorReply({5, 1, 0, 0}, MakeError(ErrorCode::kTimeout, "timeout")));
  auto index = End();
  ASSERT_TRUE(index) << index.error().message;
  auto reader = OpenRecording(path_);
  ASSERT_TRUE(reader);
  auto reply = ReadRecordedReply(**reader, *index->steps[0].reply_offset);
  ASSERT_TRUE(reply) << reply.error().message;
  ASSERT_FALSE(reply->result);
  EXPECT_EQ(reply->result.error().code, ErrorCode::kTimeout);
}

TEST_F(RecordingTest, OrderAndPairingAreChecked) {
  struct Case {
    const char* says;
    std::function<void(RecordingTest&)> write;
  };
  const auto header = [](RecordingTest& t) {
    t.Add(kRecordingHeaderChannel, testing::SampleRecordingHeader());
  };
  const auto add_record = [](RecordingTest& t, uint64_t sequence) {
    t.Add(kRecordingRingChannel, MakeRemoveObjectRingRecord(sequence, 0, 1));
  };
  const std::vector<Case> cases = {
      {"the first event must be the FARREC_HEADER", [&](RecordingTest& t) { add_record(t, 1); }},
      {"a second header",
       [&](RecordingTest& t) {
         header(t);
         header(t);
       }},
      {"is not the next one (1)",
       [&](RecordingTest& t) {
         header(t);
         add_record(t, 2);
       }},
      {"ring_commit_sequence 3 is not in [0, 1]",
       [&](RecordingTest& t) {
         header(t);
         add_record(t, 1);
         t.Add(kRecordingRequestChannel, Request(0, 3));
       }},
      {"ring_commit_sequence 0 is not in [1, 1]",
       [&](RecordingTest& t) {
         header(t);
         add_record(t, 1);
         t.Add(kRecordingRequestChannel, Request(0, 1));
         t.Add(kRecordingRequestChannel, Request(1, 0));
       }},
      {"step_id 0 is not after step 0",
       [&](RecordingTest& t) {
         header(t);
         t.Add(kRecordingRequestChannel, Request(0, 0));
         t.Add(kRecordingRequestChannel, Request(0, 0));
       }},
      {"which no recorded request asked for",
       [&](RecordingTest& t) {
         header(t);
         t.Add(kRecordingReplyChannel, Reply(0));
       }},
      {"a second reply to step 0",
       [&](RecordingTest& t) {
         header(t);
         t.Add(kRecordingRequestChannel, Request(0, 0));
         t.Add(kRecordingReplyChannel, Reply(0));
         t.Add(kRecordingReplyChannel, Reply(0));
       }},
      {"channel 'FAR_S1_REQ' is not FARREC_HEADER",
       [&](RecordingTest& t) {
         header(t);
         t.Add("FAR_S1_REQ", Request(0, 0));
       }},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.says);
    Begin();
    c.write(*this);
    ExpectRefused(ErrorCode::kParseError, c.says);
  }
}

TEST_F(RecordingTest, MessagesOfTheWrongTypeOrMeaningAreRefused) {
  Begin();
  Add(kRecordingHeaderChannel, testing::SampleRecordingHeader());
  Add(kRecordingRequestChannel, Reply(0));  // a reply on the request channel
  ExpectRefused(ErrorCode::kParseError, "fingerprint");

  Begin();
  Add(kRecordingHeaderChannel, testing::SampleRecordingHeader());
  wire::step_request_t bad = Request(0, 0);
  bad.resolution = 5;
  Add(kRecordingRequestChannel, bad);
  ExpectRefused(ErrorCode::kInvalidArgument, "resolution");

  Begin();
  Add(kRecordingHeaderChannel, testing::SampleRecordingHeader());
  Add(kRecordingRequestChannel, Request(0, 0));
  wire::step_reply_t stub = Reply(0);
  stub.reply_in_shm = true;
  Add(kRecordingReplyChannel, stub);
  ExpectRefused(ErrorCode::kParseError, "a stub");

  Begin();
  Add(kRecordingHeaderChannel, testing::SampleRecordingHeader());
  Add(kRecordingRequestChannel, Request(0, 0));
  wire::step_reply_t uneven = Reply(0);
  uneven.contact_object_a[0] = -4;  // an ok reply whose arrays do not parse
  Add(kRecordingReplyChannel, uneven);
  ExpectRefused(ErrorCode::kParseError, "contact_object_a");
}

TEST_F(RecordingTest, OtherVersionsAreNamed) {
  wire::recording_header_t header = testing::SampleRecordingHeader();
  header.format_version = 2;
  Begin();
  Add(kRecordingHeaderChannel, header);
  ExpectRefused(ErrorCode::kVersionMismatch, "recording format 2");
  header = testing::SampleRecordingHeader();
  header.protocol_version = kProtocolVersion + 1;
  Begin();
  Add(kRecordingHeaderChannel, header);
  ExpectRefused(ErrorCode::kVersionMismatch, "protocol " + std::to_string(kProtocolVersion + 1));
}

TEST_F(RecordingTest, AnEmptyFileIsNoRecording) {
  Begin();
  ExpectRefused(ErrorCode::kParseError, "no events");
}

TEST_F(RecordingTest, EveryTruncationAndByteFlipIsRefusedOrReadNeverACrash) {
  WriteGoodRecording();
  ASSERT_TRUE(End());
  std::ifstream in(path_, std::ios::binary);
  const std::vector<uint8_t> whole{std::istreambuf_iterator<char>(in),
                                   std::istreambuf_iterator<char>()};
  const std::string cut = (dir_ / "cut.farrec").string();
  const auto index_of = [&](const std::vector<uint8_t>& bytes) {
    std::ofstream(cut, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char*>(bytes.data()), static_cast<long>(bytes.size()));
    auto reader = OpenRecording(cut);
    EXPECT_TRUE(reader);
    return IndexRecording(**reader);
  };
  int accepted = 0;
  for (size_t size = 0; size < whole.size(); ++size) {
    auto index = index_of({whole.begin(), whole.begin() + static_cast<long>(size)});
    if (index) ++accepted;  // cut exactly between two events: a shorter recording
  }
  EXPECT_LE(accepted, 8);
  std::mt19937 random(7);
  for (int trial = 0; trial < 600; ++trial) {
    std::vector<uint8_t> bytes = whole;
    bytes[random() % bytes.size()] ^= static_cast<uint8_t>(1 + random() % 255);
    (void)index_of(bytes);  // refused or read, never a crash or a huge allocation
  }
}

TEST_F(RecordingTest, RingRecordsRoundTripBitForBit) {
  Pose odd = SomePose();
  odd.rotation.w() = std::nextafter(0.5, 1.0);  // a last bit that normalizing may change
  const wire::ring_record_t add =
      MakeAddObjectRingRecord(1, 0, 9, Triangle(), Motion::kDeformable, odd);
  auto parsed = ParseRingRecord(add);
  ASSERT_TRUE(parsed) << parsed.error().message;
  const auto& a = std::get<far::AddObject>(parsed->update);
  EXPECT_EQ(a.id, 9u);
  EXPECT_EQ(a.motion, Motion::kDeformable);
  EXPECT_EQ(a.X_WO.rotation.w(), odd.rotation.w());
  EXPECT_EQ(a.mesh.p_MV, Triangle().p_MV);
  EXPECT_EQ(a.mesh.triangles, Triangle().triangles);

  Mesh huge_index = Triangle();
  huge_index.triangles[0][2] = 0xFFFFFFF0u;  // the daemon refuses it; the recording keeps it
  auto kept = ParseRingRecord(MakeAddObjectRingRecord(1, 0, 9, huge_index, Motion::kStatic, odd));
  ASSERT_TRUE(kept);
  EXPECT_EQ(std::get<far::AddObject>(kept->update).mesh.triangles[0][2], 0xFFFFFFF0u);

  const std::vector<Eigen::Vector3d> moved = {{1, 2, 3}, {4, 5, 6}};
  auto vertices = ParseRingRecord(MakeSetVerticesRingRecord(2, 1, 9, moved));
  ASSERT_TRUE(vertices);
  EXPECT_EQ(std::get<far::SetVertices>(vertices->update).p_MV, moved);
  EXPECT_EQ(vertices->sequence, 2u);
  EXPECT_EQ(vertices->step_id, 1);
}

TEST_F(RecordingTest, RingRecordStructureIsChecked) {
  struct Case {
    const char* says;
    std::function<void(wire::ring_record_t&)> spoil;
  };
  const std::vector<Case> cases = {
      {"sequence: 0 is not >= 1", [](auto& r) { r.sequence = 0; }},
      {"step_id: -1 is negative", [](auto& r) { r.step_id = -1; }},
      {"object_id: 4294967296 is not a uint32", [](auto& r) { r.object_id = int64_t{1} << 32; }},
      {"type: 16 is not 1", [](auto& r) { r.type = 16; }},
      {"motion: 3 is not 0", [](auto& r) { r.motion = 3; }},
      {"num_coordinates: 8 is not 3 *",
       [](auto& r) {
         r.num_coordinates = 8;
         r.p_MV.resize(8);
       }},
      {"num_coordinates: 0 is not 3 *",
       [](auto& r) {
         r.num_coordinates = 0;
         r.p_MV.clear();
       }},
      {"p_MV: 2 values for num_coordinates 9", [](auto& r) { r.p_MV.resize(2); }},
      {"num_indices: 4 is not 3 *",
       [](auto& r) {
         r.num_indices = 4;
         r.triangles.resize(4);
       }},
      {"triangles: 1 values for num_indices 3", [](auto& r) { r.triangles.resize(1); }},
      {"motion: 1 is not 0 (unused)", [](auto& r) { r.type = 3; }},
      {"num_coordinates: 9 is not 0 (unused)",
       [](auto& r) {
         r.type = 3;
         r.motion = 0;
       }},
      {"X_WO: not zero (unused)",
       [](auto& r) {
         r.type = 2;
         r.motion = 0;
       }},
      {"num_indices: 3 is not 0 (unused)",
       [](auto& r) {
         r.type = 4;
         r.motion = 0;
         std::fill(r.X_WO, r.X_WO + 7, 0.0);
       }},
  };
  for (const Case& c : cases) {
    wire::ring_record_t record = testing::SampleRingRecord();
    c.spoil(record);
    auto parsed = ParseRingRecord(record);
    ASSERT_FALSE(parsed) << c.says;
    EXPECT_EQ(parsed.error().code, ErrorCode::kParseError);
    EXPECT_NE(parsed.error().message.find(c.says), std::string::npos) << parsed.error().message;
  }
}

}  // namespace
}  // namespace far::protocol
