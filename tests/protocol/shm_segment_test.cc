// The session segment: an anonymous memory file, sealed against resizing and handed over as a
// descriptor, checked by the client.

#include "far/protocol/shm_segment.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

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

// pwrite()s bytes into a segment through its descriptor, as its client could.
void Scribble(const ShmSegment& segment, off_t offset, const void* bytes, size_t size) {
  ASSERT_EQ(pwrite(segment.fd(), bytes, size, offset), static_cast<ssize_t>(size));
}

// Opens a copy of the daemon's descriptor, as the client gets it.
Result<std::unique_ptr<ShmSegment>> OpenCopy(const ShmSegment& daemon, uint64_t session_id) {
  return ShmSegment::Open(dup(daemon.fd()), session_id);
}

void ExpectOpenError(int fd, uint64_t session_id, ErrorCode code, const std::string& substring) {
  auto opened = ShmSegment::Open(fd, session_id);
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

TEST(ShmSegmentTest, IsAnAnonymousSealedMemoryFile) {
  auto a = CreateOrDie(17);
  auto b = CreateOrDie(17);
  ASSERT_TRUE(a && b);
  for (const ShmSegment* segment : {a.get(), b.get()}) {
    ASSERT_GE(segment->fd(), 0);
    // No name anywhere: a memfd, never in /dev/shm.
    char link[256] = {};
    const std::string proc = "/proc/self/fd/" + std::to_string(segment->fd());
    ASSERT_GT(readlink(proc.c_str(), link, sizeof(link) - 1), 0);
    EXPECT_EQ(std::string(link).rfind("/memfd:far-session-17", 0), 0u) << link;
    struct stat info {};
    EXPECT_NE(stat("/dev/shm/far-session-17", &info), 0);
    // Its size cannot change: nobody can truncate it under the daemon.
    const int seals = fcntl(segment->fd(), F_GET_SEALS);
    EXPECT_EQ(seals & (F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_SEAL),
              F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_SEAL);
    EXPECT_NE(ftruncate(segment->fd(), 4096), 0);
    EXPECT_NE(ftruncate(segment->fd(), static_cast<off_t>(segment->layout().segment_size * 2)), 0);
    ASSERT_EQ(fstat(segment->fd(), &info), 0);
    EXPECT_EQ(static_cast<uint64_t>(info.st_size), segment->layout().segment_size);
    // Every page is allocated up front (no SIGBUS later when memory runs out).
    EXPECT_GE(static_cast<uint64_t>(info.st_blocks) * 512, segment->layout().segment_size);
  }
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
  auto client = OpenCopy(*daemon, 5);
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

TEST(ShmSegmentTest, OpenRejectsDescriptorsThatAreNotSealedSegments) {
  ExpectOpenError(-1, 1, ErrorCode::kInvalidArgument, "no file descriptor");
  // An unsealed memory file: its owner could shrink it under the client's mapping.
  const int plain = memfd_create("plain", MFD_CLOEXEC);
  ASSERT_GE(plain, 0);
  ASSERT_EQ(ftruncate(plain, 1 << 20), 0);
  ExpectOpenError(plain, 1, ErrorCode::kPermissionDenied, "not a memory file sealed");
  int pipe_fds[2];
  ASSERT_EQ(pipe(pipe_fds), 0);
  close(pipe_fds[1]);
  ExpectOpenError(pipe_fds[0], 1, ErrorCode::kPermissionDenied, "not a memory file sealed");
}

TEST(ShmSegmentTest, OpenChecksSessionAndHeader) {
  auto daemon = CreateOrDie(8);
  ASSERT_TRUE(daemon);
  ExpectOpenError(dup(daemon->fd()), 9, ErrorCode::kParseError, "segment: session_id 8 is not 9");

  const uint32_t version = kLayoutVersion + 1;
  Scribble(*daemon, offsetof(SegmentHeader, layout_version), &version, sizeof(version));
  ExpectOpenError(dup(daemon->fd()), 8, ErrorCode::kVersionMismatch,
                  "segment: layout_version: got 2, expected 1");
  Scribble(*daemon, offsetof(SegmentHeader, layout_version), &kLayoutVersion, sizeof(version));

  const uint64_t capacity = kMinRingCapacity + 8;
  Scribble(*daemon, offsetof(SegmentHeader, reply_ring_capacity), &capacity, sizeof(capacity));
  ExpectOpenError(dup(daemon->fd()), 8, ErrorCode::kParseError, "ring capacities");
  Scribble(*daemon, offsetof(SegmentHeader, reply_ring_capacity), &kMinRingCapacity,
           sizeof(capacity));

  const uint64_t size = daemon->layout().segment_size + 4096;
  Scribble(*daemon, offsetof(SegmentHeader, segment_size), &size, sizeof(size));
  ExpectOpenError(dup(daemon->fd()), 8, ErrorCode::kParseError, "differs from the file size");
  const uint64_t right = daemon->layout().segment_size;
  Scribble(*daemon, offsetof(SegmentHeader, segment_size), &right, sizeof(right));

  const uint64_t magic = 0x1122334455667788;
  Scribble(*daemon, 0, &magic, sizeof(magic));
  ExpectOpenError(dup(daemon->fd()), 8, ErrorCode::kParseError,
                  "segment: magic 0x1122334455667788 is not FARRING");
}

// The memory a descriptor's file holds: its allocated blocks, in bytes.
int64_t AllocatedBytes(int fd) {
  struct stat info {};
  EXPECT_EQ(fstat(fd, &info), 0);
  return static_cast<int64_t>(info.st_blocks) * 512;
}

// A segment of 1 MiB rings, its client's mapping, and a copy of the descriptor the client kept.
struct KeptSegment {
  std::unique_ptr<ShmSegment> daemon, client;
  int kept = -1;
  ~KeptSegment() {
    if (kept >= 0) close(kept);
  }
};

void MakeKept(KeptSegment& s, uint64_t session_id) {
  s.daemon = CreateOrDie(session_id, {1 << 20, 1 << 20});
  ASSERT_TRUE(s.daemon);
  s.kept = dup(s.daemon->fd());
  auto client = OpenCopy(*s.daemon, session_id);
  ASSERT_TRUE(client) << client.error().message;
  s.client = std::move(*client);
}

TEST(ShmSegmentTest, ReleaseFreesTheMemoryThatTheClientsDescriptorAndMappingHold) {
  KeptSegment s;
  MakeKept(s, 3);
  ASSERT_TRUE(s.client);
  const auto size = static_cast<int64_t>(s.daemon->layout().segment_size);
  UpdateWriter writer(s.client->update_ring());
  ASSERT_TRUE(writer.AddObject(1, Triangle(), Motion::kRigid, {}));
  EXPECT_GE(AllocatedBytes(s.kept), size) << "allocated whole when made";

  ASSERT_TRUE(s.daemon->Release());
  EXPECT_EQ(AllocatedBytes(s.kept), 0) << "the kept descriptor still holds memory";
  // Both mappings stay valid and read zeros: the rings are empty, nothing faulted.
  UpdateReader reader(s.daemon->update_ring(), RingLimits{});
  auto updates = reader.Drain(0);
  ASSERT_TRUE(updates) << updates.error().message;
  EXPECT_TRUE(updates->empty());
  EXPECT_FALSE(s.daemon->faulted());
  EXPECT_FALSE(s.client->faulted());
  EXPECT_TRUE(s.daemon->Release()) << "idempotent";
}

TEST(ShmSegmentTest, DestroyingTheDaemonsSegmentFreesItsMemoryWhileTheClientKeepsItsOwn) {
  KeptSegment s;
  MakeKept(s, 4);
  ASSERT_TRUE(s.client);
  ASSERT_GT(AllocatedBytes(s.kept), 0);
  s.daemon.reset();
  EXPECT_EQ(AllocatedBytes(s.kept), 0);
  // What the client touches afterwards is its own memory again, and it still works.
  UpdateWriter writer(s.client->update_ring());
  ASSERT_TRUE(writer.AddObject(1, Triangle(), Motion::kRigid, {}));
  EXPECT_GT(AllocatedBytes(s.kept), 0);
  EXPECT_LT(AllocatedBytes(s.kept), 64 << 10);
}

TEST(ShmSegmentTest, TheClientCannotSealTheSegmentAgainstRelease) {
  KeptSegment s;
  MakeKept(s, 5);
  ASSERT_TRUE(s.client);
  // F_SEAL_FUTURE_WRITE (or F_SEAL_WRITE) would make the punch fail; F_SEAL_SEAL forbids both.
  for (const int seal : {F_SEAL_WRITE, F_SEAL_FUTURE_WRITE}) {
    EXPECT_NE(fcntl(s.kept, F_ADD_SEALS, seal), 0);
    EXPECT_EQ(errno, EPERM);
  }
  ASSERT_TRUE(s.daemon->Release());
  EXPECT_EQ(AllocatedBytes(s.kept), 0);
}

TEST(ShmSegmentTest, OnlyTheDaemonReleasesTheSegment) {
  KeptSegment s;
  MakeKept(s, 6);
  ASSERT_TRUE(s.client);
  auto released = s.client->Release();
  ASSERT_FALSE(released);
  EXPECT_EQ(released.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(released.error().message.find("only the daemon releases it"), std::string::npos)
      << released.error().message;
  EXPECT_GT(AllocatedBytes(s.kept), 0);
}

}  // namespace
}  // namespace far::protocol
