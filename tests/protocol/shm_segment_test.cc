// The session segment: owner-only and unguessable, checked by the client, and a daemon that
// survives a client truncating it.

#include "far/protocol/shm_segment.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <regex>
#include <set>

#include <gtest/gtest.h>

#include "far/protocol/ring_records.h"

namespace far::protocol {
namespace {

SegmentOptions Small() { return {kMinRingCapacity, kMinRingCapacity}; }

std::unique_ptr<ShmSegment> CreateOrDie(uint64_t session_id, SegmentOptions options = Small()) {
  auto segment = ShmSegment::Create(session_id, options);
  EXPECT_TRUE(segment) << segment.error().message;
  return segment ? std::move(*segment) : nullptr;
}

// pwrite()s bytes into a segment by name, as another process of the same user could.
void Scribble(const std::string& name, off_t offset, const void* bytes, size_t size) {
  const int fd = shm_open(name.c_str(), O_RDWR, 0);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(pwrite(fd, bytes, size, offset), static_cast<ssize_t>(size));
  close(fd);
}

void ExpectOpenError(const std::string& name, uint64_t session_id, ErrorCode code,
                     const std::string& substring) {
  auto opened = ShmSegment::Open(name, session_id);
  ASSERT_FALSE(opened) << "opened; expected " << substring;
  EXPECT_EQ(opened.error().code, code) << opened.error().message;
  EXPECT_NE(opened.error().message.find(substring), std::string::npos) << opened.error().message;
}

Mesh Triangle() {
  Mesh mesh;
  mesh.p_MV = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{{0, 1, 2}}};
  return mesh;
}

TEST(ShmSegmentTest, IsOwnerOnlyWithAnUnguessableName) {
  auto a = CreateOrDie(17);
  auto b = CreateOrDie(17);
  ASSERT_TRUE(a && b);
  for (const ShmSegment* segment : {a.get(), b.get()}) {
    struct stat info {};
    ASSERT_EQ(stat(("/dev/shm" + segment->name()).c_str(), &info), 0);
    EXPECT_EQ(info.st_mode & 07777, 0600u);
    EXPECT_EQ(info.st_uid, geteuid());
    EXPECT_EQ(static_cast<uint64_t>(info.st_size), segment->layout().segment_size);
    // "/far-<pid>-<session>-<32 hex>": 128 random bits.
    const std::regex pattern("/far-" + std::to_string(getpid()) + "-17-([0-9a-f]{32})");
    std::smatch match;
    ASSERT_TRUE(std::regex_match(segment->name(), match, pattern)) << segment->name();
    const std::string hex = match[1].str();
    const std::set<char> distinct(hex.begin(), hex.end());
    EXPECT_GE(distinct.size(), 6u);  // not a constant or a counter
    EXPECT_TRUE(IsValidSegmentName(segment->name()));
  }
  EXPECT_NE(a->name(), b->name());
  EXPECT_NE(a->session_key(), b->session_key());
}

TEST(ShmSegmentTest, CreateRejectsBadArguments) {
  auto zero = ShmSegment::Create(0, Small());
  ASSERT_FALSE(zero);
  EXPECT_EQ(zero.error().code, ErrorCode::kInvalidArgument);
  auto odd = ShmSegment::Create(1, {kMinRingCapacity + 8, kMinRingCapacity});
  ASSERT_FALSE(odd);
  EXPECT_NE(odd.error().message.find("is not a power of two"), std::string::npos);
}

TEST(ShmSegmentTest, ClientSeesTheLayoutAndKeyAndSharesTheRings) {
  auto daemon = CreateOrDie(5, {uint64_t{1} << 17, kMinRingCapacity});
  ASSERT_TRUE(daemon);
  auto client = ShmSegment::Open(daemon->name(), 5);
  ASSERT_TRUE(client) << client.error().message;
  EXPECT_FALSE((*client)->owner());
  EXPECT_EQ((*client)->session_key(), daemon->session_key());
  EXPECT_EQ((*client)->layout().update_ring_capacity, uint64_t{1} << 17);
  EXPECT_EQ((*client)->layout().reply_ring_offset, daemon->layout().reply_ring_offset);

  // Update ring: client -> daemon.
  UpdateWriter writer((*client)->update_ring());
  UpdateReader reader(daemon->update_ring(), RingLimits{});
  ASSERT_TRUE(writer.AddObject(1, Triangle(), Motion::kRigid, {}));
  auto updates = reader.Drain(writer.last_sequence());
  ASSERT_TRUE(updates) << updates.error().message;
  ASSERT_EQ(updates->size(), 1u);
  EXPECT_EQ(std::get<AddObject>((*updates)[0].update).mesh.p_MV, Triangle().p_MV);

  // Reply ring: daemon -> client.
  RingWriter replies(daemon->reply_ring());
  RingReader client_replies((*client)->reply_ring(), kMinRingCapacity);
  const std::vector<uint8_t> payload = {1, 2, 3, 4, 5, 6, 7, 8};
  ASSERT_TRUE(replies.Write(RecordType::kStepReply, {payload}));
  auto next = client_replies.ReadNext();
  ASSERT_TRUE(next && next->has_value());
  EXPECT_EQ((*next)->header.type, static_cast<uint32_t>(RecordType::kStepReply));
}

TEST(ShmSegmentTest, OpenRejectsNamesThatAreNotFarSegments) {
  ExpectOpenError("/etc/passwd", 1, ErrorCode::kInvalidArgument, "is not a far segment name");
  ExpectOpenError("far-1-1-0123456789abcdef0123456789abcdef", 1, ErrorCode::kInvalidArgument,
                  "is not a far segment name");
  ExpectOpenError("/far-1-1-0123456789ABCDEF0123456789ABCDEF", 1, ErrorCode::kInvalidArgument,
                  "is not a far segment name");
  ExpectOpenError("/far-1-1-../../../../etc/passwd00000000000", 1, ErrorCode::kInvalidArgument,
                  "is not a far segment name");
  ExpectOpenError("/far-1-1-0123456789abcdef0123456789abcdef", 1, ErrorCode::kNotFound,
                  "No such file");
}

TEST(ShmSegmentTest, OpenChecksSessionModeAndHeader) {
  auto daemon = CreateOrDie(8);
  ASSERT_TRUE(daemon);
  const std::string name = daemon->name();
  ExpectOpenError(name, 9, ErrorCode::kParseError, "segment: session_id 8 is not 9");

  // Group/other bits: refused (someone else could have written it).
  const int fd = shm_open(name.c_str(), O_RDWR, 0);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(fchmod(fd, 0644), 0);
  ExpectOpenError(name, 8, ErrorCode::kPermissionDenied, "with mode 0644; expected this user");
  ASSERT_EQ(fchmod(fd, 0600), 0);
  close(fd);

  const uint32_t version = kLayoutVersion + 1;
  Scribble(name, offsetof(SegmentHeader, layout_version), &version, sizeof(version));
  ExpectOpenError(name, 8, ErrorCode::kVersionMismatch,
                  "segment: layout_version: got 2, expected 1");
  Scribble(name, offsetof(SegmentHeader, layout_version), &kLayoutVersion, sizeof(version));

  const uint64_t capacity = kMinRingCapacity + 8;
  Scribble(name, offsetof(SegmentHeader, reply_ring_capacity), &capacity, sizeof(capacity));
  ExpectOpenError(name, 8, ErrorCode::kParseError, "ring capacities");
  Scribble(name, offsetof(SegmentHeader, reply_ring_capacity), &kMinRingCapacity, sizeof(capacity));

  const uint64_t magic = 0x1122334455667788;
  Scribble(name, 0, &magic, sizeof(magic));
  ExpectOpenError(name, 8, ErrorCode::kParseError,
                  "segment: magic 0x1122334455667788 is not FARRING");
}

TEST(ShmSegmentTest, OpenRejectsAFileSizeThatDiffersFromTheHeader) {
  auto daemon = CreateOrDie(8);
  ASSERT_TRUE(daemon);
  const int fd = shm_open(daemon->name().c_str(), O_RDWR, 0);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(ftruncate(fd, static_cast<off_t>(daemon->layout().segment_size + 4096)), 0);
  close(fd);
  ExpectOpenError(daemon->name(), 8, ErrorCode::kParseError, "differs from the file size");
}

TEST(ShmSegmentTest, DaemonSurvivesAClientTruncatingTheSegment) {
  auto daemon = CreateOrDie(3);
  ASSERT_TRUE(daemon);
  auto client = ShmSegment::Open(daemon->name(), 3);
  ASSERT_TRUE(client);
  UpdateWriter writer((*client)->update_ring());
  UpdateReader reader(daemon->update_ring(), RingLimits{});
  ASSERT_TRUE(writer.AddObject(1, Triangle(), Motion::kRigid, {}));

  // The client shrinks the file to its header page: the ring pages are now past the end of
  // the file, and touching them raises SIGBUS.
  const int fd = shm_open(daemon->name().c_str(), O_RDWR, 0);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(ftruncate(fd, 4096), 0);
  close(fd);

  auto updates = reader.Drain(1);
  ASSERT_FALSE(updates);
  EXPECT_EQ(updates.error().code, ErrorCode::kParseError);
  EXPECT_NE(updates.error().message.find("truncated by its peer (SIGBUS caught)"),
            std::string::npos)
      << updates.error().message;
  EXPECT_TRUE(daemon->faulted());
  EXPECT_TRUE(reader.corrupt());

  // Writing a reply into the truncated segment fails the same way (no crash).
  RingWriter replies(daemon->reply_ring());
  const std::vector<uint8_t> payload(64, 1);
  auto written = replies.Write(RecordType::kStepReply, {payload});
  ASSERT_FALSE(written);
  EXPECT_NE(written.error().message.find("truncated"), std::string::npos);
}

TEST(ShmSegmentTest, DaemonUnlinksOnDestruction) {
  auto daemon = CreateOrDie(4);
  ASSERT_TRUE(daemon);
  const std::string name = daemon->name();
  daemon.reset();
  struct stat info {};
  EXPECT_NE(stat(("/dev/shm" + name).c_str(), &info), 0);
  ExpectOpenError(name, 4, ErrorCode::kNotFound, "No such file");
}

TEST(ShmSegmentTest, RemoveStaleSegmentsRemovesOnlyThoseOfDeadDaemons) {
  // A pid that surely is dead: a child that exited and was reaped.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) _exit(0);
  ASSERT_EQ(waitpid(child, nullptr, 0), child);
  const std::string stale = "/far-" + std::to_string(child) + "-1-" + std::string(32, 'a');
  const int fd = shm_open(stale.c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
  ASSERT_GE(fd, 0);
  close(fd);
  auto live = CreateOrDie(6);
  ASSERT_TRUE(live);

  // A name with a pid that does not fit any integer: skipped, no exception.
  const std::string absurd = "/far-99999999999999999999-1-" + std::string(32, 'b');
  const int absurd_fd = shm_open(absurd.c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
  ASSERT_GE(absurd_fd, 0);
  close(absurd_fd);

  EXPECT_GE(RemoveStaleSegments(), 1);
  struct stat info {};
  EXPECT_NE(stat(("/dev/shm" + stale).c_str(), &info), 0);
  EXPECT_EQ(stat(("/dev/shm" + live->name()).c_str(), &info), 0);
  EXPECT_EQ(stat(("/dev/shm" + absurd).c_str(), &info), 0);
  shm_unlink(absurd.c_str());
}

}  // namespace
}  // namespace far::protocol
