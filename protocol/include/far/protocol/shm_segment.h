#pragma once

// A session's shared-memory segment (layout in ring_layout.h), created by the daemon and
// mapped by the client. POSIX shm (shm_open) with mode 0600: only processes of the daemon's
// user can open it, so clients run as the daemon's user. The name carries 128 random bits
// ("/far-<daemon pid>-<session id>-<32 hex digits>"), so no other process can pre-create
// (squat) it or find it by guessing.
//
// The daemon never trusts the segment's contents: it keeps the layout and the session key
// privately and reads only the client-owned ring indices (checked on every load) and records
// (copied out, then checked). A client that shrinks the segment (ftruncate) would make the
// daemon's next access raise SIGBUS; every access runs under a guard that turns that into
// faulted() == true and a kParseError from the ring (see src/shm_access.h).

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "far/model/result.h"
#include "far/protocol/ring.h"
#include "far/protocol/ring_layout.h"
#include "far/protocol/session_auth.h"

namespace far::protocol {

namespace internal {
struct MappedRange;
}  // namespace internal

/// Ring capacities of a new segment (bytes, IsValidRingCapacity).
struct SegmentOptions {
  uint64_t update_ring_bytes = uint64_t{16} << 20;
  uint64_t reply_ring_bytes = uint64_t{16} << 20;
};

/// One mapping of a session segment. Not copyable; RingRegions it hands out alias the
/// mapping and must not outlive it. Thread safety: const accessors from any thread; each
/// ring side from one thread.
class ShmSegment {
 public:
  /// Daemon: creates the segment (O_CREAT | O_EXCL, mode exactly 0600), sizes and maps it and
  /// writes the header, with a fresh session key (NewSessionKey). The segment is unlinked when
  /// this object is destroyed. Errors: kInvalidArgument (bad capacities, session_id 0),
  /// kUnavailable (shm_open, ftruncate or mmap failed; the message has errno's text).
  static Result<std::unique_ptr<ShmSegment>> Create(uint64_t session_id,
                                                    const SegmentOptions& options = {});

  /// Client: opens and maps an existing segment (read-write) and checks it: a regular file
  /// owned by this user with mode 0600, a size within bounds, then the header: magic,
  /// layout_version (kVersionMismatch), header_size, segment_size equal to the file size,
  /// session_id equal to `session_id`, valid capacities and offsets. Errors: kInvalidArgument
  /// (the name is not a far segment name), kNotFound, kPermissionDenied (owner or mode),
  /// kParseError (header), kVersionMismatch, kUnavailable.
  static Result<std::unique_ptr<ShmSegment>> Open(std::string_view name, uint64_t session_id);

  ~ShmSegment();
  ShmSegment(const ShmSegment&) = delete;
  ShmSegment& operator=(const ShmSegment&) = delete;

  /// The POSIX shm name, starting with '/'.
  const std::string& name() const { return name_; }
  uint64_t session_id() const { return session_id_; }
  /// The MAC key of the session's LCM messages (private copy).
  const SessionKey& session_key() const { return key_; }
  /// The layout (private copy; the daemon never re-reads the header).
  const SegmentLayout& layout() const { return layout_; }
  /// True for the daemon's (creating) mapping.
  bool owner() const { return owner_; }
  /// True once a SIGBUS showed that the peer truncated the segment; every ring operation
  /// fails from then on.
  bool faulted() const;

  /// The update ring (client writes, daemon reads) and the reply ring (daemon writes, client
  /// reads) of this mapping.
  RingRegion update_ring() const;
  RingRegion reply_ring() const;

  /// Removes the name (owner only; idempotent). Mappings stay valid.
  void Unlink();

 private:
  ShmSegment() = default;
  // The ring at `offset` of this mapping with its two published indices.
  RingRegion Ring(uint64_t offset, uint64_t capacity, std::atomic<uint64_t>* write_index,
                  std::atomic<uint64_t>* read_index, const char* name) const;

  std::string name_;
  uint64_t session_id_ = 0;
  SessionKey key_{};
  SegmentLayout layout_;
  bool owner_ = false;
  bool unlinked_ = false;
  SegmentHeader* header_ = nullptr;
  std::unique_ptr<internal::MappedRange> mapping_;
};

/// True when `name` has the form "/far-<pid>-<session id>-<32 lower-case hex digits>".
bool IsValidSegmentName(std::string_view name);

/// Daemon start-up: removes segments "/far-<pid>-..." of this user whose daemon process
/// <pid> no longer exists (left behind by a SIGKILLed daemon). Returns how many it removed.
int RemoveStaleSegments();

}  // namespace far::protocol
