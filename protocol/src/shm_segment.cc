#include "far/protocol/shm_segment.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cinttypes>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <new>

#include "shm_access.h"

namespace far::protocol {
namespace {

std::string ErrnoText(int error) { return std::strerror(error); }

std::string Hex64(uint64_t value) {
  char text[24];
  std::snprintf(text, sizeof(text), "0x%016" PRIx64, value);
  return text;
}

bool AllDigits(std::string_view text) {
  if (text.empty() || text.size() > 20) return false;
  for (const char c : text) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

// Splits "far-<pid>-<session>-<hex>" (no leading '/'); false when it does not have that form.
bool SplitName(std::string_view name, std::string_view* pid) {
  constexpr std::string_view kPrefix = "far-";
  if (name.substr(0, kPrefix.size()) != kPrefix) return false;
  name.remove_prefix(kPrefix.size());
  const size_t first = name.find('-');
  if (first == std::string_view::npos) return false;
  const size_t second = name.find('-', first + 1);
  if (second == std::string_view::npos) return false;
  const std::string_view pid_text = name.substr(0, first);
  const std::string_view session_text = name.substr(first + 1, second - first - 1);
  const std::string_view hex = name.substr(second + 1);
  if (!AllDigits(pid_text) || !AllDigits(session_text) || hex.size() != 32) return false;
  for (const char c : hex) {
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  if (pid != nullptr) *pid = pid_text;
  return true;
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

bool IsValidSegmentName(std::string_view name) {
  return !name.empty() && name[0] == '/' && SplitName(name.substr(1), nullptr);
}

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

  // An unguessable name: 128 random bits.
  uint8_t random[16];
  RandomBytes(random, sizeof(random));
  char hex[33];
  for (size_t i = 0; i < sizeof(random); ++i) std::snprintf(hex + 2 * i, 3, "%02x", random[i]);
  segment->name_ = "/far-" + std::to_string(getpid()) + "-" + std::to_string(session_id) + "-" +
                   std::string(hex, 32);

  // Create exclusively, owner-only; umask can only remove bits, fchmod makes it exact.
  const int fd = shm_open(segment->name_.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) {
    return MakeError(ErrorCode::kUnavailable,
                     "segment: shm_open(" + segment->name_ + ") failed: " + ErrnoText(errno));
  }
  const uint64_t size = segment->layout_.segment_size;
  auto fail = [&](const char* what) {
    const int error = errno;
    close(fd);
    shm_unlink(segment->name_.c_str());
    return MakeError(ErrorCode::kUnavailable, "segment: " + std::string(what) + "(" +
                                                  segment->name_ + ") failed: " + ErrnoText(error));
  };
  if (fchmod(fd, 0600) != 0) return fail("fchmod");
  if (ftruncate(fd, static_cast<off_t>(size)) != 0) return fail("ftruncate");
  void* base = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  if (base == MAP_FAILED) return fail("mmap");
  close(fd);
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
                     "segment: " + segment->name_ + " could not be written (out of shm space?)");
  }
  return segment;
}

Result<std::unique_ptr<ShmSegment>> ShmSegment::Open(std::string_view name, uint64_t session_id) {
  if (!IsValidSegmentName(name)) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "segment: '" + std::string(name.substr(0, 80)) +
                         "' is not a far segment name (/far-<pid>-<session>-<32 hex>)");
  }
  std::unique_ptr<ShmSegment> segment(new ShmSegment());
  segment->name_ = std::string(name);
  segment->session_id_ = session_id;
  const int fd = shm_open(segment->name_.c_str(), O_RDWR | O_CLOEXEC | O_NOFOLLOW, 0);
  if (fd < 0) {
    const int error = errno;
    return MakeError(error == ENOENT ? ErrorCode::kNotFound : ErrorCode::kUnavailable,
                     "segment: shm_open(" + segment->name_ + ") failed: " + ErrnoText(error));
  }
  // The file itself: ours, owner-only, a plausible size.
  struct stat info {};
  if (fstat(fd, &info) != 0) {
    const int error = errno;
    close(fd);
    return MakeError(ErrorCode::kUnavailable, "segment: fstat failed: " + ErrnoText(error));
  }
  if (!S_ISREG(info.st_mode) || info.st_uid != geteuid() || (info.st_mode & 07777) != 0600) {
    close(fd);
    char mode[8];
    std::snprintf(mode, sizeof(mode), "%04o", static_cast<unsigned>(info.st_mode & 07777));
    return MakeError(ErrorCode::kPermissionDenied,
                     "segment: " + segment->name_ + " is owned by uid " +
                         std::to_string(info.st_uid) + " with mode " + mode +
                         "; expected this user (uid " + std::to_string(geteuid()) +
                         ") and mode 0600");
  }
  const auto size = static_cast<uint64_t>(info.st_size);
  if (size < kRingAlignment + 2 * kMinRingCapacity ||
      size > kRingAlignment + 2 * kMaxRingCapacity) {
    close(fd);
    return MakeError(ErrorCode::kParseError,
                     "segment: size " + std::to_string(size) + " is out of bounds");
  }
  void* base = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  const int mmap_error = errno;
  close(fd);
  if (base == MAP_FAILED) {
    return MakeError(ErrorCode::kUnavailable, "segment: mmap failed: " + ErrnoText(mmap_error));
  }
  segment->mapping_ = std::make_unique<internal::MappedRange>();
  segment->mapping_->base = static_cast<uint8_t*>(base);
  segment->mapping_->size = size;

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
  segment->layout_ = expected;
  std::memcpy(segment->key_.data(), h.session_key, kSessionKeyBytes);
  segment->header_ = static_cast<SegmentHeader*>(base);
  return segment;
}

ShmSegment::~ShmSegment() {
  if (mapping_ != nullptr) munmap(mapping_->base, mapping_->size);
  if (owner_) Unlink();
}

void ShmSegment::Unlink() {
  if (owner_ && !unlinked_) {
    shm_unlink(name_.c_str());
    unlinked_ = true;
  }
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

int RemoveStaleSegments() {
  DIR* dir = opendir("/dev/shm");
  if (dir == nullptr) return 0;
  int removed = 0;
  const uid_t me = geteuid();
  while (dirent* entry = readdir(dir)) {
    const std::string_view name = entry->d_name;
    std::string_view pid_text;
    if (!SplitName(name, &pid_text)) continue;
    // The name comes from a directory anyone can write to: parse without throwing.
    int64_t pid = 0;
    const auto parsed = std::from_chars(pid_text.data(), pid_text.data() + pid_text.size(), pid);
    if (parsed.ec != std::errc() || pid <= 0 || pid > INT32_MAX || pid == getpid()) continue;
    // Still running (or not ours to signal): leave it.
    if (kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;
    struct stat info {};
    const std::string path = "/dev/shm/" + std::string(name);
    if (lstat(path.c_str(), &info) != 0 || !S_ISREG(info.st_mode) || info.st_uid != me) continue;
    if (shm_unlink(("/" + std::string(name)).c_str()) == 0) ++removed;
  }
  closedir(dir);
  return removed;
}

}  // namespace far::protocol
