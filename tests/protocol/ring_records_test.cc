// Update records: UpdateWriter -> UpdateReader round trips, and records a hostile client forges.

#include "far/protocol/ring_records.h"

#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "test_ring.h"
#include <gtest/gtest.h>

namespace far::protocol {
namespace {

using testing::TestRing;

Mesh Tetrahedron(double scale) {
  Mesh mesh;
  mesh.p_MV = {{0, 0, 0}, {scale, 0, 0}, {0, scale, 0}, {0, 0, scale}};
  mesh.triangles = {{{0, 2, 1}}, {{0, 1, 3}}, {{0, 3, 2}}, {{1, 2, 3}}};
  return mesh;
}

Pose MakePose(double x, double angle) {
  Pose pose;
  pose.translation = Eigen::Vector3d(x, -2.5, 1e5);
  pose.rotation =
      Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d(1, 2, 3).normalized()));
  return pose;
}

template <typename T>
void Put(std::vector<uint8_t>& bytes, size_t offset, const T& value) {
  if (bytes.size() < offset + sizeof(T)) bytes.resize(offset + sizeof(T));
  std::memcpy(bytes.data() + offset, &value, sizeof(T));
}

// A forged add_object record; `size` 0 means the size the counts imply.
std::vector<uint8_t> ForgeAddObject(uint64_t sequence, uint32_t id, uint32_t motion,
                                    uint32_t vertex_count, uint32_t triangle_count,
                                    const std::vector<double>& pose,
                                    const std::vector<double>& positions,
                                    const std::vector<uint32_t>& triangles, uint32_t size = 0) {
  std::vector<uint8_t> bytes(sizeof(AddObjectRecord), 0);
  Put(bytes, 16, id);
  Put(bytes, 20, motion);
  Put(bytes, 24, vertex_count);
  Put(bytes, 28, triangle_count);
  for (size_t i = 0; i < pose.size(); ++i) Put(bytes, 32 + 8 * i, pose[i]);
  size_t at = sizeof(AddObjectRecord);
  for (const double p : positions) Put(bytes, (at += 8) - 8, p);
  for (const uint32_t t : triangles) Put(bytes, (at += 4) - 4, t);
  bytes.resize(AlignRecordSize(bytes.size()), 0);
  const uint32_t record_size = size != 0 ? size : static_cast<uint32_t>(bytes.size());
  bytes.resize(record_size, 0);
  const RecordHeader header{static_cast<uint32_t>(RecordType::kAddObject), record_size, sequence};
  std::memcpy(bytes.data(), &header, sizeof(header));
  return bytes;
}

const std::vector<double> kIdentity = {0, 0, 0, 1, 0, 0, 0};
const std::vector<double> kTriangle = {0, 0, 0, 1, 0, 0, 0, 1, 0};

std::vector<uint8_t> ForgeSetPose(uint64_t sequence, uint32_t id, const std::vector<double>& pose,
                                  uint32_t reserved = 0) {
  std::vector<uint8_t> bytes(sizeof(SetPoseRecord), 0);
  const RecordHeader header{static_cast<uint32_t>(RecordType::kSetPose), 80, sequence};
  std::memcpy(bytes.data(), &header, sizeof(header));
  Put(bytes, 16, id);
  Put(bytes, 20, reserved);
  for (size_t i = 0; i < pose.size(); ++i) Put(bytes, 24 + 8 * i, pose[i]);
  return bytes;
}

std::vector<uint8_t> ForgeRemove(uint64_t sequence, uint32_t id, uint32_t reserved = 0,
                                 uint32_t size = 24) {
  std::vector<uint8_t> bytes(size, 0);
  const RecordHeader header{static_cast<uint32_t>(RecordType::kRemoveObject), size, sequence};
  std::memcpy(bytes.data(), &header, sizeof(header));
  Put(bytes, 16, id);
  Put(bytes, 20, reserved);
  return bytes;
}

std::vector<uint8_t> ForgeSetVertices(uint64_t sequence, uint32_t id, uint32_t vertex_count,
                                      const std::vector<double>& positions, uint32_t size = 0) {
  std::vector<uint8_t> bytes(sizeof(SetVerticesRecord), 0);
  Put(bytes, 16, id);
  Put(bytes, 20, vertex_count);
  for (size_t i = 0; i < positions.size(); ++i) Put(bytes, 24 + 8 * i, positions[i]);
  bytes.resize(AlignRecordSize(bytes.size()), 0);
  const uint32_t record_size = size != 0 ? size : static_cast<uint32_t>(bytes.size());
  bytes.resize(record_size, 0);
  const RecordHeader header{static_cast<uint32_t>(RecordType::kSetVertices), record_size, sequence};
  std::memcpy(bytes.data(), &header, sizeof(header));
  return bytes;
}

void ExpectParseError(const std::vector<uint8_t>& record, ErrorCode code,
                      const std::string& substring, const RingLimits& limits = {}) {
  auto parsed = ParseUpdateRecord(record, limits);
  ASSERT_FALSE(parsed) << "accepted a bad record; expected: " << substring;
  EXPECT_EQ(parsed.error().code, code) << parsed.error().message;
  EXPECT_NE(parsed.error().message.find(substring), std::string::npos) << parsed.error().message;
}

// ---- round trips ------------------------------------------------------------------------------

TEST(UpdateRingTest, RoundTripsEveryRecordType) {
  TestRing ring(1 << 16, "update ring");
  UpdateWriter writer(ring.region());
  UpdateReader reader(ring.region(), RingLimits{});
  const Mesh mesh = Tetrahedron(0.1 + 1.0 / 3.0);
  const Pose pose = MakePose(1.0 / 7.0, 0.3);
  const Pose pose2 = MakePose(-3.25, 2.0);
  const std::vector<Eigen::Vector3d> moved = {
      {1e-300, 2, 3}, {-4, 5.5, 6}, {7, 8, -9e8}, {0.1, 0.2, 0.3}};
  ASSERT_TRUE(writer.AddObject(7, mesh, Motion::kDeformable, pose));
  ASSERT_TRUE(writer.SetPose(7, pose2));
  ASSERT_TRUE(writer.SetVertices(7, moved));
  ASSERT_TRUE(writer.RemoveObject(7));
  EXPECT_EQ(writer.last_sequence(), 4u);

  auto updates = reader.Drain(writer.last_sequence());
  ASSERT_TRUE(updates) << updates.error().message;
  ASSERT_EQ(updates->size(), 4u);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ((*updates)[i].sequence, i + 1);

  const auto& add = std::get<AddObject>((*updates)[0].update);
  EXPECT_EQ(add.id, 7u);
  EXPECT_EQ(add.motion, Motion::kDeformable);
  EXPECT_EQ(add.mesh.p_MV, mesh.p_MV);  // bit-exact doubles
  EXPECT_EQ(add.mesh.triangles, mesh.triangles);
  EXPECT_EQ(add.X_WO.translation, pose.translation);
  EXPECT_EQ(add.X_WO.rotation.coeffs(), pose.rotation.coeffs());

  const auto& set_pose = std::get<SetPose>((*updates)[1].update);
  EXPECT_EQ(set_pose.id, 7u);
  EXPECT_EQ(set_pose.X_WO.translation, pose2.translation);
  EXPECT_EQ(set_pose.X_WO.rotation.coeffs(), pose2.rotation.coeffs());

  const auto& set_vertices = std::get<SetVertices>((*updates)[2].update);
  EXPECT_EQ(set_vertices.id, 7u);
  EXPECT_EQ(set_vertices.p_MV, moved);

  EXPECT_EQ(std::get<RemoveObject>((*updates)[3].update).id, 7u);
}

TEST(UpdateRingTest, RoundTripsAcrossTheRingEndManyTimes) {
  TestRing ring(4096, "update ring");
  UpdateWriter writer(ring.region());
  UpdateReader reader(ring.region(), RingLimits{});
  for (int step = 0; step < 300; ++step) {
    const Mesh mesh = Tetrahedron(1.0 + step);
    ASSERT_TRUE(writer.AddObject(static_cast<uint32_t>(step), mesh, Motion::kRigid,
                                 MakePose(step, 0.01 * step)));
    ASSERT_TRUE(writer.SetPose(static_cast<uint32_t>(step), MakePose(-step, 0.02 * step)));
    auto updates = reader.Drain(writer.last_sequence());
    ASSERT_TRUE(updates) << step << ": " << updates.error().message;
    ASSERT_EQ(updates->size(), 2u);
    EXPECT_EQ(std::get<AddObject>((*updates)[0].update).mesh.p_MV, mesh.p_MV) << step;
  }
  EXPECT_GT(ring.write_index.load(), 20 * 4096u);
}

TEST(UpdateRingTest, DrainUpToLastSequenceReturnsNothing) {
  TestRing ring(4096, "update ring");
  UpdateReader reader(ring.region(), RingLimits{});
  auto updates = reader.Drain(0);
  ASSERT_TRUE(updates);
  EXPECT_TRUE(updates->empty());
}

// ---- all-or-nothing per step -------------------------------------------------------------------

TEST(UpdateRingTest, BadRecordDiscardsTheWholeStepAndTheSessionGoesOn) {
  TestRing ring(4096, "update ring");
  UpdateWriter writer(ring.region());
  UpdateReader reader(ring.region(), RingLimits{});
  // Step 1: fine.
  ASSERT_TRUE(writer.AddObject(1, Tetrahedron(1), Motion::kRigid, {}));
  auto step1 = reader.Drain(1);
  ASSERT_TRUE(step1) << step1.error().message;
  // Step 2: records 2..4, the middle one with a NaN translation.
  ASSERT_TRUE(writer.SetPose(1, MakePose(1, 0)));
  Pose bad = MakePose(1, 0);
  bad.translation.y() = std::numeric_limits<double>::quiet_NaN();
  ASSERT_TRUE(writer.SetPose(1, bad));
  ASSERT_TRUE(writer.RemoveObject(1));
  auto step2 = reader.Drain(4);
  ASSERT_FALSE(step2);
  EXPECT_EQ(step2.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(step2.error().message.find("record 3 (set_pose): X_WO.t.y: nan is not finite"),
            std::string::npos)
      << step2.error().message;
  EXPECT_NE(step2.error().message.find("records 2..4 of this step were discarded"),
            std::string::npos);
  EXPECT_EQ(reader.last_sequence(), 4u);
  EXPECT_FALSE(reader.corrupt());
  // Step 3: the client writes again; the ring works.
  ASSERT_TRUE(writer.RemoveObject(1));
  auto step3 = reader.Drain(5);
  ASSERT_TRUE(step3) << step3.error().message;
  ASSERT_EQ(step3->size(), 1u);
  EXPECT_EQ((*step3)[0].sequence, 5u);
}

TEST(UpdateRingTest, ValidatesItsCopyNotWhatTheClientWritesLater) {
  TestRing ring(4096, "update ring");
  UpdateWriter writer(ring.region());
  UpdateReader reader(ring.region(), RingLimits{});
  ASSERT_TRUE(writer.SetPose(3, MakePose(2, 0.5)));
  auto raw = reader.ring().ReadUpTo(1);
  ASSERT_TRUE(raw);
  // After the copy, the client overwrites the record with NaNs and a bogus size.
  std::fill(ring.data.begin(), ring.data.end(), 0xFF);
  auto parsed = ParseUpdateRecord((*raw)[0].bytes, RingLimits{});
  ASSERT_TRUE(parsed) << parsed.error().message;
  EXPECT_EQ(std::get<SetPose>(*parsed).X_WO.translation, MakePose(2, 0.5).translation);
}

TEST(UpdateRingTest, OverwriteDuringTheCopyIsCaughtByValidatingTheCopy) {
  TestRing ring(4096, "update ring");
  UpdateWriter writer(ring.region());
  UpdateReader reader(ring.region(), RingLimits{});
  ASSERT_TRUE(writer.SetPose(3, MakePose(2, 0.5)));
  // Between the header check and the body copy the client writes a NaN into the pose.
  reader.ring().SetCopyHookForTesting([&](const RecordHeader&) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    std::memcpy(ring.data.data() + offsetof(SetPoseRecord, X_WO), &nan, sizeof(nan));
  });
  auto updates = reader.Drain(1);
  ASSERT_FALSE(updates);
  EXPECT_NE(updates.error().message.find("X_WO.t.x: nan is not finite"), std::string::npos)
      << updates.error().message;
}

TEST(UpdateRingTest, RecordCommittedBeforeItsBodyWasWrittenIsRejectedWithoutCrashing) {
  // A client bug: it advanced write_index past a record whose body it never wrote.
  TestRing ring(4096, "update ring");
  UpdateReader reader(ring.region(), RingLimits{});
  std::vector<uint8_t> header_only(176, 0);
  const RecordHeader header{static_cast<uint32_t>(RecordType::kAddObject), 176, 1};
  std::memcpy(header_only.data(), &header, sizeof(header));
  ring.Append(header_only);
  auto updates = reader.Drain(1);
  ASSERT_FALSE(updates);
  EXPECT_EQ(updates.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(updates.error().message.find("vertex_count: 0 is not >= 1"), std::string::npos)
      << updates.error().message;
}

TEST(UpdateRingTest, ForgedRecordsInTheRingAreValidated) {
  TestRing ring(4096, "update ring");
  UpdateReader reader(ring.region(), RingLimits{});
  ring.Append(ForgeAddObject(1, 5, 1, 3, 1, kIdentity, kTriangle, {0, 1, 2}));
  ring.Append(ForgeAddObject(2, 6, 1, 3, 1, kIdentity, kTriangle, {0, 1, 3}));
  auto updates = reader.Drain(2);
  ASSERT_FALSE(updates);
  EXPECT_NE(updates.error().message.find(
                "record 2 (add_object): triangles[0][2]: 3 is not < vertex_count 3"),
            std::string::npos)
      << updates.error().message;
}

TEST(UpdateRingTest, SurvivesRandomCorruptionOfRingBytesAndIndices) {
  // Valid records, then random bytes and write indices: every Drain returns (an error or
  // updates that passed validation), nothing crashes or reads out of bounds (ASan build).
  std::mt19937 random(777);
  TestRing pristine(4096, "update ring");
  {
    UpdateWriter writer(pristine.region());
    ASSERT_TRUE(writer.AddObject(1, Tetrahedron(1), Motion::kDeformable, MakePose(1, 0.2)));
    ASSERT_TRUE(writer.SetPose(1, MakePose(2, 0.3)));
    const std::vector<Eigen::Vector3d> moved(4, Eigen::Vector3d(1, 2, 3));
    ASSERT_TRUE(writer.SetVertices(1, moved));
    ASSERT_TRUE(writer.RemoveObject(1));
  }
  const uint64_t committed = pristine.write_index.load();
  int accepted = 0;
  for (int i = 0; i < 3000; ++i) {
    TestRing ring(4096, "update ring");
    ring.data = pristine.data;
    const int flips = 1 + static_cast<int>(random() % 6);
    for (int k = 0; k < flips; ++k) {
      ring.data[random() % committed] = static_cast<uint8_t>(random());
    }
    ring.write_index = (i % 5 == 0) ? random() % 8192 : committed;
    UpdateReader reader(ring.region(), RingLimits{});
    auto updates = reader.Drain(1 + random() % 5);
    if (updates) {
      ++accepted;
      for (const auto& update : *updates) {
        if (const auto* add = std::get_if<AddObject>(&update.update)) {
          for (const auto& triangle : add->mesh.triangles) {
            for (const uint32_t v : triangle) EXPECT_LT(v, add->mesh.p_MV.size());
          }
        }
      }
    }
  }
  EXPECT_GT(accepted, 0);
}

// ---- hostile records, one check each ------------------------------------------------------------

TEST(ParseUpdateRecordTest, AcceptsAValidForgedRecord) {
  auto parsed = ParseUpdateRecord(ForgeAddObject(1, 5, 2, 3, 1, kIdentity, kTriangle, {0, 1, 2}),
                                  RingLimits{});
  ASSERT_TRUE(parsed) << parsed.error().message;
  const auto& add = std::get<AddObject>(*parsed);
  EXPECT_EQ(add.id, 5u);
  EXPECT_EQ(add.motion, Motion::kDeformable);
  EXPECT_EQ(add.mesh.num_vertices(), 3);
}

TEST(ParseUpdateRecordTest, RejectsUnknownType) {
  auto record = ForgeRemove(1, 5);
  record[0] = 99;
  ExpectParseError(record, ErrorCode::kInvalidArgument, "type: 99 is not an update record type");
}

TEST(ParseUpdateRecordTest, RejectsAReplyRecordInTheUpdateRing) {
  auto record = ForgeRemove(1, 5);
  record[0] = static_cast<uint8_t>(RecordType::kStepReply);
  ExpectParseError(record, ErrorCode::kInvalidArgument, "type: 16 is not an update record type");
}

TEST(ParseUpdateRecordTest, RejectsCountsWhoseByteSizeOverflows32Bits) {
  RingLimits no_limits;
  no_limits.max_vertices = 0xFFFFFFFFu;
  no_limits.max_triangles = 0xFFFFFFFFu;
  // 24 * 2^32 + 12 * 2^32 bytes wrap to a small number in 32-bit arithmetic.
  ExpectParseError(
      ForgeAddObject(1, 5, 1, 0xFFFFFFFFu, 0xFFFFFFFFu, kIdentity, kTriangle, {0, 1, 2}),
      ErrorCode::kInvalidArgument,
      "size: 176 does not match vertex_count 4294967295 and triangle_count "
      "4294967295 (expected 154618822712)",
      no_limits);
  // 24 + 24 * 2863311531 is 32 modulo 2^32: a 32-byte record would pass a 32-bit check.
  ExpectParseError(ForgeSetVertices(1, 5, 0xAAAAAAABu, {}, 32), ErrorCode::kInvalidArgument,
                   "size: 32 does not match vertex_count 2863311531 (expected 68719476768)",
                   no_limits);
}

TEST(ParseUpdateRecordTest, RejectsCountsOverLimits) {
  RingLimits limits;
  limits.max_vertices = 2;
  ExpectParseError(ForgeAddObject(1, 5, 1, 3, 1, kIdentity, kTriangle, {0, 1, 2}),
                   ErrorCode::kLimitExceeded, "vertex_count: 3 is over the limit 2", limits);
  ExpectParseError(ForgeSetVertices(1, 5, 3, kTriangle), ErrorCode::kLimitExceeded,
                   "vertex_count: 3 is over the limit 2", limits);
  RingLimits triangles;
  triangles.max_triangles = 1;
  ExpectParseError(ForgeAddObject(1, 5, 1, 3, 2, kIdentity, kTriangle, {0, 1, 2, 0, 2, 1}),
                   ErrorCode::kLimitExceeded, "triangle_count: 2 is over the limit 1", triangles);
}

TEST(ParseUpdateRecordTest, RejectsZeroCounts) {
  ExpectParseError(ForgeAddObject(1, 5, 1, 3, 0, kIdentity, kTriangle, {}),
                   ErrorCode::kInvalidArgument, "triangle_count: 0 is not >= 1");
  ExpectParseError(ForgeSetVertices(1, 5, 0, {}), ErrorCode::kInvalidArgument,
                   "vertex_count: 0 is not >= 1");
}

TEST(ParseUpdateRecordTest, RejectsSizesThatDoNotMatchTheCounts) {
  ExpectParseError(ForgeAddObject(1, 5, 1, 3, 1, kIdentity, kTriangle, {0, 1, 2}, 184),
                   ErrorCode::kInvalidArgument,
                   "size: 184 does not match vertex_count 3 and triangle_count 1 (expected 176)");
  ExpectParseError(ForgeAddObject(1, 5, 1, 3, 1, kIdentity, kTriangle, {0, 1, 2}, 40),
                   ErrorCode::kInvalidArgument, "size: 40 is smaller than an add_object record");
  ExpectParseError(ForgeRemove(1, 5, 0, 32), ErrorCode::kInvalidArgument,
                   "size: 32 does not match remove_object (expected 24)");
  ExpectParseError(ForgeSetVertices(1, 5, 3, kTriangle, 104), ErrorCode::kInvalidArgument,
                   "size: 104 does not match vertex_count 3 (expected 96)");
}

TEST(ParseUpdateRecordTest, RejectsIndicesOutOfRange) {
  ExpectParseError(
      ForgeAddObject(1, 5, 1, 3, 2, kIdentity, kTriangle, {0, 1, 2, 2, 0xFFFFFFFFu, 0}),
      ErrorCode::kInvalidArgument, "triangles[1][1]: 4294967295 is not < vertex_count 3");
}

TEST(ParseUpdateRecordTest, RejectsNonFinitePositions) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  ExpectParseError(
      ForgeAddObject(1, 5, 1, 3, 1, kIdentity, {0, 0, 0, 1, nan, 0, 0, 1, 0}, {0, 1, 2}),
      ErrorCode::kInvalidArgument, "p_MV[1].y: nan is not finite");
  ExpectParseError(ForgeSetVertices(1, 5, 3, {0, 0, 0, 1, 0, 0, 0, 1, -inf}),
                   ErrorCode::kInvalidArgument, "p_MV[2].z: -inf is not finite");
  ExpectParseError(ForgeSetVertices(1, 5, 3, {0, 0, 0, 1, 0, 0, 0, 1e13, 0}),
                   ErrorCode::kInvalidArgument, "p_MV[2].y: 1e+13 is beyond +-1e+12");
}

TEST(ParseUpdateRecordTest, RejectsNonFinitePoses) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  ExpectParseError(ForgeSetPose(1, 5, {inf, 0, 0, 1, 0, 0, 0}), ErrorCode::kInvalidArgument,
                   "record 1 (set_pose): X_WO.t.x: inf is not finite");
  ExpectParseError(ForgeSetPose(1, 5, {0, 0, 0, 1, 0, nan, 0}), ErrorCode::kInvalidArgument,
                   "X_WO.q.y: nan is not finite");
  ExpectParseError(ForgeAddObject(9, 5, 1, 3, 1, {0, 0, 0, inf, 0, 0, 0}, kTriangle, {0, 1, 2}),
                   ErrorCode::kInvalidArgument,
                   "record 9 (add_object): X_WO.q.w: inf is not finite");
}

TEST(ParseUpdateRecordTest, RejectsNonUnitQuaternions) {
  // The rule is the model's (far::CheckPose); the record names the field it came from.
  ExpectParseError(ForgeSetPose(1, 5, {0, 0, 0, 1, 1, 0, 0}), ErrorCode::kInvalidArgument,
                   "record 1 (set_pose): X_WO: rotation_wxyz: not a unit quaternion (norm "
                   "1.41421356)");
  ExpectParseError(ForgeSetPose(1, 5, {0, 0, 0, 0, 0, 0, 0}), ErrorCode::kInvalidArgument,
                   "not a unit quaternion (norm 0)");
  ExpectParseError(ForgeSetPose(1, 5, {0, 0, 0, 1 + 2e-3, 0, 0, 0}), ErrorCode::kInvalidArgument,
                   "not a unit quaternion (norm 1.002): |norm - 1| must be at most 0.001");
}

// Within the tolerance (a quaternion written with four decimals): accepted as sent, bit for bit
// (far::Pipeline normalizes where it places the object).
TEST(ParseUpdateRecordTest, AcceptsNearlyUnitQuaternions) {
  const auto parsed =
      ParseUpdateRecord(ForgeSetPose(1, 5, {0, 0, 0, 0.7071, 0, 0, 0.7071}), RingLimits{});
  ASSERT_TRUE(parsed) << ToString(parsed.error());
  const auto* set_pose = std::get_if<SetPose>(&*parsed);
  ASSERT_NE(set_pose, nullptr);
  EXPECT_EQ(set_pose->X_WO.rotation.w(), 0.7071);
  const auto added = ParseUpdateRecord(
      ForgeAddObject(2, 5, 1, 3, 1, {0, 0, 0, 1.0009, 0, 0, 0}, kTriangle, {0, 1, 2}),
      RingLimits{});
  ASSERT_TRUE(added) << ToString(added.error());
}

TEST(ParseUpdateRecordTest, RejectsUnknownMotionAndReservedBitsAcceptsEveryId) {
  ExpectParseError(ForgeAddObject(1, 5, 3, 3, 1, kIdentity, kTriangle, {0, 1, 2}),
                   ErrorCode::kInvalidArgument, "motion: 3 is not 0 (static), 1 (rigid) or 2");
  // Ids are every uint32, as in scene files (far/base/limits.h).
  for (uint32_t id : {0u, 0x80000000u, 0xFFFFFFFFu}) {
    auto parsed = ParseUpdateRecord(ForgeRemove(1, id), RingLimits{});
    ASSERT_TRUE(parsed) << parsed.error().message;
    EXPECT_EQ(std::get<far::RemoveObject>(*parsed).id, id);
  }
  ExpectParseError(ForgeRemove(1, 5, 1), ErrorCode::kInvalidArgument, "reserved: 1 is not 0");
  ExpectParseError(ForgeSetPose(1, 5, kIdentity, 7), ErrorCode::kInvalidArgument,
                   "reserved: 7 is not 0");
}

TEST(ParseUpdateRecordTest, RejectsRecordsShorterThanAHeader) {
  const std::vector<uint8_t> short_record(8, 0);
  ExpectParseError(short_record, ErrorCode::kInvalidArgument, "shorter than its header");
}

}  // namespace
}  // namespace far::protocol
