#pragma once

#include <mutex>

namespace far {

/// The process's GL lock: far's GL work on different threads takes turns under it. GlContext
/// takes it to make and destroy a context, and the pipeline for each axis view of a GPU culling
/// stage, the making and freeing of its renderers and the GPU cost probe; code that issues GL
/// calls of its own on a context of a process where pipelines run on other threads should take
/// it too.
///
/// Why: Mesa's llvmpipe shares one rasterizer (its threads and scene queue) between every
/// context of a display, and with 8 or 16 daemon sessions culling at once on their own threads
/// and contexts far-daemon died of SIGSEGV inside swrast_dri.so (Mesa 22.3.6) within seconds
/// (docs/daemon.md, "Sessions and the GL driver"). Serial GL views lose little: llvmpipe
/// rasterizes one scene at a time anyway, and a GPU's driver time-slices its contexts.
/// Recursive, so that a holder may call code that takes it again.
[[nodiscard]] std::unique_lock<std::recursive_mutex> LockGl();

}  // namespace far
