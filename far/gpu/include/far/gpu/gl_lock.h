#pragma once

#include <cstdint>

namespace far {

class GlLock;

/// Takes the process's GL lock: far's GL work on different threads takes turns under it.
/// GlContext takes it to make and destroy a context, and the pipeline for each axis view of a
/// GPU culling stage, the making and freeing of its renderers and the GPU cost probe; code that
/// issues GL calls of its own on a context of a process where pipelines run on other threads
/// should take it too.
///
/// Why: Mesa's llvmpipe shares one rasterizer (its threads and scene queue) between every
/// context of a display, and with 8 or 16 daemon sessions culling at once on their own threads
/// and contexts far-daemon died of SIGSEGV inside swrast_dri.so (Mesa 22.3.6) within seconds
/// (docs/daemon.md, "Sessions and the GL driver"). Serial GL work loses little: llvmpipe
/// rasterizes one scene at a time anyway, and a GPU's driver time-slices its contexts.
///
/// Fair: threads get the lock in the order they asked for it (a ticket lock), so that a long
/// view that hands it over between its batches of draws (GlLock::Yield) lets every thread that
/// waits have one turn before it goes on. Recursive: a holder may take it again.
[[nodiscard]] GlLock LockGl();

/// Milliseconds the calling thread has spent waiting for the GL lock since it started (in
/// LockGl and GlLock::Yield): time a step spent behind other threads' GL work, not its own.
double GlLockWaitedMs();

/// The GL lock, held from LockGl until destruction. Not movable: one scope holds it.
class GlLock {
 public:
  GlLock(const GlLock&) = delete;
  GlLock& operator=(const GlLock&) = delete;
  ~GlLock();

  /// How many other threads are waiting for the lock now.
  int waiters() const;
  /// Whether another thread is waiting for the lock now.
  bool contended() const { return waiters() > 0; }
  /// Lets every thread that waits for the lock now have its turn, in order, then takes it back
  /// (and returns how long that took, ms); returns 0 at once when none waits, or when this
  /// thread holds the lock more than once (an outer holder, such as the GPU cost probe, keeps
  /// it for the whole of its work). @pre the caller's GL work is finished (glFinish): nothing
  /// of it may run while another context's does.
  double Yield();

 private:
  friend GlLock LockGl();
  GlLock();
};

}  // namespace far
