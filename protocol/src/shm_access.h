#pragma once

// Survives a peer that truncates a shared-memory segment. Touching a page of a MAP_SHARED
// mapping beyond the end of its (shrunk) file raises SIGBUS, which would kill the daemon. The
// same happens when tmpfs runs out of space. Like Wayland's wl_shm, every access to a segment
// runs inside a ScopedShmAccess: a SIGBUS at an address inside the segment that the current
// thread is accessing replaces the whole mapping with private zero pages (mmap MAP_FIXED, a
// plain system call) and sets `faulted`; the access then reads zeros and finishes, and the
// caller checks `faulted` and reports the segment as broken. A SIGBUS anywhere else goes to
// the previous handler (default: the process dies as usual).

#include <csignal>
#include <cstddef>
#include <cstdint>

namespace far::protocol::internal {

/// One mapping of a segment in this process.
struct MappedRange {
  uint8_t* base = nullptr;
  size_t size = 0;
  volatile std::sig_atomic_t faulted = 0;  ///< set by the SIGBUS handler
};

/// Marks `range` as accessed by this thread for the scope's lifetime (nests; null is allowed
/// and guards nothing). Installs the process-wide SIGBUS handler on first use.
class ScopedShmAccess {
 public:
  explicit ScopedShmAccess(MappedRange* range);
  ~ScopedShmAccess();
  ScopedShmAccess(const ScopedShmAccess&) = delete;
  ScopedShmAccess& operator=(const ScopedShmAccess&) = delete;

  /// True when the segment was truncated (now, or before this scope began).
  bool faulted() const { return range_ != nullptr && range_->faulted != 0; }

 private:
  MappedRange* range_;
  MappedRange* previous_;
};

}  // namespace far::protocol::internal
