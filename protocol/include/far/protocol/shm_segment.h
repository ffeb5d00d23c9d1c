#pragma once

// A session's shared-memory segment (layout in ring_layout.h): an anonymous memory file
// (memfd_create) made by the daemon and handed to its client as a file descriptor over the
// daemon's local socket (SCM_RIGHTS). It has no name: no other process can open it, whatever
// its user, and nothing is left in /dev/shm when either side dies. Its pages are allocated
// when it is made (fallocate), so a full memory budget is an error at open, never a SIGBUS
// later; and it is sealed against resizing and further seals (F_SEAL_SHRINK | F_SEAL_GROW |
// F_SEAL_SEAL), so the client can neither truncate it under the daemon nor seal it against the
// daemon's Release.
//
// Its memory lives no longer than the session: the daemon keeps its descriptor and Release()s
// the memory when the session ends, whatever descriptors or mappings the client still holds
// (a client that kept the descriptor of a closed session holds an empty file: a page it
// touches again is its own, charged to it like any memory it allocates).
//
// The daemon never trusts the segment's contents: it keeps the layout and the session key
// privately and reads only the client-owned ring indices (checked on every load) and records
// (copied out, then checked). Every access still runs under a guard that turns a SIGBUS into
// faulted() == true and a kParseError from the ring (see src/shm_access.h): defence in depth.

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "far/base/result.h"
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
  /// Daemon: creates the segment (memfd), allocates, seals and maps it and writes the header,
  /// with a fresh session key (NewSessionKey). fd() is the descriptor to send to the client.
  /// Errors: kInvalidArgument (bad capacities, session_id 0), kUnavailable (no memory for the
  /// segment, or memfd_create/fallocate/mmap failed; the message has errno's text).
  static Result<std::unique_ptr<ShmSegment>> Create(uint64_t session_id,
                                                    const SegmentOptions& options = {});

  /// Client: maps the segment behind `fd` (taking ownership of it: it is closed) and checks
  /// it: a regular file sealed against shrinking and growing, a size within bounds, then the
  /// header: magic, layout_version (kVersionMismatch), header_size, segment_size equal to the
  /// file size, session_id equal to `session_id`, valid capacities and offsets. Errors:
  /// kPermissionDenied (not sealed), kParseError (header), kVersionMismatch, kUnavailable.
  static Result<std::unique_ptr<ShmSegment>> Open(int fd, uint64_t session_id);

  ~ShmSegment();
  ShmSegment(const ShmSegment&) = delete;
  ShmSegment& operator=(const ShmSegment&) = delete;

  /// A name for logs: "far-session-<id>" (the segment itself has none).
  const std::string& name() const { return name_; }
  /// The daemon's descriptor of the segment, to send to the client; -1 on the client (which
  /// closes its own once mapped).
  int fd() const { return fd_; }
  /// Daemon: frees the segment's memory now (a hole punched over the whole file), whoever
  /// still holds a descriptor or a mapping of it: the client, a copy it kept after the session
  /// closed. Both sides' mappings stay valid and read zeros; a page touched afterwards is a new
  /// page, charged to the process that touches it. The session ends with it (the rings hold
  /// nothing any more). Idempotent; the destructor calls it. Thread safety: any thread, also
  /// while another thread reads or writes the rings (under the SIGBUS guard, as always).
  /// Errors: kInvalidArgument (the client's mapping: it has no descriptor), kUnavailable
  /// (fallocate failed; errno's text).
  Result<void> Release();
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
  int fd_ = -1;
  SegmentHeader* header_ = nullptr;
  std::unique_ptr<internal::MappedRange> mapping_;
};

}  // namespace far::protocol
