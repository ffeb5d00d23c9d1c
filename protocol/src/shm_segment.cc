#include "far/protocol/shm_segment.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cinttypes>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <new>

#include "errno_text.h"
#include "shm_access.h"

namespace far::protocol {
namespace {

std::string Hex64(uint64_t value) {
  char text[24];
  std::snprintf(text, sizeof(text), "0x%016" PRIx64, value);
  return text;
}

// The constant part of a SegmentHeader, read field by field from a private copy of its bytes.
struct HeaderCopy {
  uint64_t magic;
  uint32_t layout_version;
  uint32_t header_size;
  uint64_t segment_size;
  uint64_t session_id;
  uint64_t update_ring_offset;
  uint64_t update_ring_capacity;
  uint64_t reply_ring_offset;
  uint64_t reply_ring_capacity;
  uint8_t session_key[kSessionKeyBytes];
};

template <typename T>
void ReadField(const uint8_t* bytes, size_t offset, T* out) {
  std::memcpy(out, bytes + offset, sizeof(T));
}

HeaderCopy CopyHeader(const uint8_t* bytes) {
  HeaderCopy h{};
  ReadField(bytes, offsetof(SegmentHeader, magic), &h.magic);
  ReadField(bytes, offsetof(SegmentHeader, layout_version), &h.layout_version);
  ReadField(bytes, offsetof(SegmentHeader, header_size), &h.header_size);
  ReadField(bytes, offsetof(SegmentHeader, segment_size), &h.segment_size);
  ReadField(bytes, offsetof(SegmentHeader, session_id), &h.session_id);
  ReadField(bytes, offsetof(SegmentHeader, update_ring_offset), &h.update_ring_offset);
  ReadField(bytes, offsetof(SegmentHeader, update_ring_capacity), &h.update_ring_capacity);
  ReadField(bytes, offsetof(SegmentHeader, reply_ring_offset), &h.reply_ring_offset);
  ReadField(bytes, offsetof(SegmentHeader, reply_ring_capacity), &h.reply_ring_capacity);
  std::memcpy(h.session_key, bytes + offsetof(SegmentHeader, session_key), kSessionKeyBytes);
  return h;
}

}  // namespace

Result<std::unique_ptr<ShmSegment>> ShmSegment::Create(uint64_t session_id,
                                                       const SegmentOptions& options) {
  if (session_id == 0) {
    return MakeError(ErrorCode::kInvalidArgument, "segment: session_id 0 is not valid");
  }
  for (const uint64_t capacity : {options.update_ring_bytes, options.reply_ring_bytes}) {
    if (!IsValidRingCapacity(capacity)) {
      return MakeError(ErrorCode::kInvalidArgument,
                       "segment: ring capacity " + std::to_string(capacity) +
                           " is not a power of two in [" + std::to_string(kMinRingCapacity) + ", " +
                           std::to_string(kMaxRingCapacity) + "]");
    }
  }
  std::unique_ptr<ShmSegment> segment(new ShmSegment());
  segment->session_id_ = session_id;
  segment->owner_ = true;
  segment->layout_ = MakeSegmentLayout(options.update_ring_bytes, options.reply_ring_bytes);

  segment->name_ = "far-session-" + std::to_string(session_id);
  const int fd = memfd_create(segment->name_.c_str(), MFD_CLOEXEC | MFD_ALLOW_SEALING);
  if (fd < 0) {
    return MakeError(ErrorCode::kUnavailable, "segment: memfd_create failed: " + ErrnoText(errno));
  }
  const uint64_t size = segment->layout_.segment_size;
  auto fail = [&](const char* what) {
    const int error = errno;
    close(fd);
    if (error == ENOSPC || error == ENOMEM) {
      return MakeError(ErrorCode::kUnavailable, "segment: no memory for " + std::to_string(size) +
                                                    " bytes of shared memory (" + what + ": " +
                                                    ErrnoText(error) + ")");
    }
    return MakeError(ErrorCode::kUnavailable,
                     "segment: " + std::string(what) + " failed: " + ErrnoText(error));
  };
  if (ftruncate(fd, static_cast<off_t>(size)) != 0) return fail("ftruncate");
  // Every page now, so that running out of memory is this error and not a SIGBUS mid-step.
  if (fallocate(fd, 0, 0, static_cast<off_t>(size)) != 0) return fail("fallocate");
  if (fcntl(fd, F_ADD_SEALS, F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_SEAL) != 0)
    return fail("F_ADD_SEALS");
  void* base = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  if (base == MAP_FAILED) return fail("mmap");
  segment->fd_ = fd;
  segment->mapping_ = std::make_unique<internal::MappedRange>();
  segment->mapping_->base = static_cast<uint8_t*>(base);
  segment->mapping_->size = size;

  // The header: constant part, then the key; indices start at 0 (fresh pages are zero).
  segment->key_ = NewSessionKey();
  internal::ScopedShmAccess access(segment->mapping_.get());
  auto* header = new (base) SegmentHeader();
  header->magic = kSegmentMagic;
  header->layout_version = kLayoutVersion;
  header->header_size = sizeof(SegmentHeader);
  header->segment_size = size;
  header->session_id = session_id;
  header->update_ring_offset = segment->layout_.update_ring_offset;
  header->update_ring_capacity = segment->layout_.update_ring_capacity;
  header->reply_ring_offset = segment->layout_.reply_ring_offset;
  header->reply_ring_capacity = segment->layout_.reply_ring_capacity;
  std::memcpy(header->session_key, segment->key_.data(), kSessionKeyBytes);
  std::atomic_thread_fence(std::memory_order_release);
  segment->header_ = header;
  if (access.faulted()) {
    return MakeError(ErrorCode::kUnavailable,
                     "segment: " + segment->name_ + " could not be written");
  }
  return segment;
}

namespace {

// The size of a segment file the daemon is handed, once it is known to be a memory file
// sealed against resizing (nobody can change its size under the mapping) of a size within the
// rings' bounds. Closes `fd` when it is not.
Result<uint64_t> SealedSegmentSize(int fd) {
  struct stat info {};
  if (fstat(fd, &info) != 0) {
    const int error = errno;
    close(fd);
    return MakeError(ErrorCode::kUnavailable, "segment: fstat failed: " + ErrnoText(error));
  }
  const int seals = fcntl(fd, F_GET_SEALS);
  if (!S_ISREG(info.st_mode) || seals < 0 ||
      (seals & (F_SEAL_SHRINK | F_SEAL_GROW)) != (F_SEAL_SHRINK | F_SEAL_GROW)) {
    close(fd);
    return MakeError(ErrorCode::kPermissionDenied,
                     "segment: the descriptor is not a memory file sealed against resizing");
  }
  const auto size = static_cast<uint64_t>(info.st_size);
  if (size < kRingAlignment + 2 * kMinRingCapacity ||
      size > kRingAlignment + 2 * kMaxRingCapacity) {
    close(fd);
    return MakeError(ErrorCode::kParseError,
                     "segment: size " + std::to_string(size) + " is out of bounds");
  }
  return size;
}

// Checks the header's constant part against the file's size and the session, and returns the
// layout it describes.
Result<SegmentLayout> CheckHeader(const HeaderCopy& h, uint64_t size, uint64_t session_id) {
  if (h.magic != kSegmentMagic) {
    return MakeError(ErrorCode::kParseError, "segment: magic " + Hex64(h.magic) +
                                                 " is not FARRING (" + Hex64(kSegmentMagic) + ")");
  }
  if (h.layout_version != kLayoutVersion) {
    return MakeError(ErrorCode::kVersionMismatch,
                     "segment: layout_version: got " + std::to_string(h.layout_version) +
                         ", expected " + std::to_string(kLayoutVersion));
  }
  if (h.header_size != sizeof(SegmentHeader)) {
    return MakeError(ErrorCode::kParseError, "segment: header_size " +
                                                 std::to_string(h.header_size) + " is not " +
                                                 std::to_string(sizeof(SegmentHeader)));
  }
  if (h.segment_size != size) {
    return MakeError(ErrorCode::kParseError,
                     "segment: segment_size " + std::to_string(h.segment_size) +
                         " differs from the file size " + std::to_string(size));
  }
  if (h.session_id != session_id) {
    return MakeError(ErrorCode::kParseError, "segment: session_id " + std::to_string(h.session_id) +
                                                 " is not " + std::to_string(session_id));
  }
  if (!IsValidRingCapacity(h.update_ring_capacity) || !IsValidRingCapacity(h.reply_ring_capacity)) {
    return MakeError(ErrorCode::kParseError,
                     "segment: ring capacities " + std::to_string(h.update_ring_capacity) + ", " +
                         std::to_string(h.reply_ring_capacity) + " are not valid");
  }
  const SegmentLayout expected = MakeSegmentLayout(h.update_ring_capacity, h.reply_ring_capacity);
  if (h.update_ring_offset != expected.update_ring_offset ||
      h.reply_ring_offset != expected.reply_ring_offset || expected.segment_size != size) {
    return MakeError(ErrorCode::kParseError,
                     "segment: ring offsets " + std::to_string(h.update_ring_offset) + ", " +
                         std::to_string(h.reply_ring_offset) + " do not match the layout");
  }
  return expected;
}

}  // namespace

Result<std::unique_ptr<ShmSegment>> ShmSegment::Open(int fd, uint64_t session_id) {
  std::unique_ptr<ShmSegment> segment(new ShmSegment());
  segment->name_ = "far-session-" + std::to_string(session_id);
  segment->session_id_ = session_id;
  if (fd < 0) return MakeError(ErrorCode::kInvalidArgument, "segment: no file descriptor");
  const Result<uint64_t> size = SealedSegmentSize(fd);
  if (!size) return size.error();
  void* base = mmap(nullptr, *size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  const int mmap_error = errno;
  close(fd);
  if (base == MAP_FAILED) {
    return MakeError(ErrorCode::kUnavailable, "segment: mmap failed: " + ErrnoText(mmap_error));
  }
  segment->mapping_ = std::make_unique<internal::MappedRange>();
  segment->mapping_->base = static_cast<uint8_t*>(base);
  segment->mapping_->size = *size;

  // The header's constant part, copied once and checked.
  uint8_t constants[offsetof(SegmentHeader, update_write_index)];
  {
    internal::ScopedShmAccess access(segment->mapping_.get());
    std::memcpy(constants, base, sizeof(constants));
    if (access.faulted()) {
      return MakeError(ErrorCode::kParseError, "segment: truncated while its header was read");
    }
  }
  const HeaderCopy h = CopyHeader(constants);
  const Result<SegmentLayout> layout = CheckHeader(h, *size, session_id);
  if (!layout) return layout.error();
  segment->layout_ = *layout;
  std::memcpy(segment->key_.data(), h.session_key, kSessionKeyBytes);
  segment->header_ = static_cast<SegmentHeader*>(base);
  return segment;
}

ShmSegment::~ShmSegment() {
  // The daemon's: what its last accesses touched again goes too, before the mapping does.
  if (fd_ >= 0) (void)Release();
  if (mapping_ != nullptr) munmap(mapping_->base, mapping_->size);
  if (fd_ >= 0) close(fd_);
}

Result<void> ShmSegment::Release() {
  if (fd_ < 0) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "segment: " + name_ + " is the client's mapping; only the daemon releases it");
  }
  // F_SEAL_WRITE would forbid the punch; the daemon sealed the file with F_SEAL_SEAL, so no one
  // can have added it.
  if (fallocate(fd_, FALLOC_FL_PUNCH_HOLE | FALLOC_FL_KEEP_SIZE, 0,
                static_cast<off_t>(layout_.segment_size)) != 0) {
    return MakeError(ErrorCode::kUnavailable,
                     "segment: releasing " + name_ + " failed: " + ErrnoText(errno));
  }
  return {};
}

bool ShmSegment::faulted() const { return mapping_ != nullptr && mapping_->faulted != 0; }

RingRegion ShmSegment::Ring(uint64_t offset, uint64_t capacity, std::atomic<uint64_t>* write_index,
                            std::atomic<uint64_t>* read_index, const char* name) const {
  RingRegion region;
  region.data = mapping_->base + offset;
  region.capacity = capacity;
  region.write_index = write_index;
  region.read_index = read_index;
  region.mapping = mapping_.get();
  region.name = name;
  return region;
}

RingRegion ShmSegment::update_ring() const {
  return Ring(layout_.update_ring_offset, layout_.update_ring_capacity,
              &header_->update_write_index, &header_->update_read_index, "update ring");
}

RingRegion ShmSegment::reply_ring() const {
  return Ring(layout_.reply_ring_offset, layout_.reply_ring_capacity, &header_->reply_write_index,
              &header_->reply_read_index, "reply ring");
}

}  // namespace far::protocol
