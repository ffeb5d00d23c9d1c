#pragma once

#include <cstdint>

namespace far {

/// Work the scene bookkeeping did since the pipeline was made: what "only what changed is
/// recomputed or re-uploaded" is tested against.
struct SceneCounters {
  int64_t world_updates = 0;  ///< objects whose world-frame vertices were recomputed
  int64_t piece_builds = 0;   ///< (object, offset kind) GPU piece sets built from vertices
  int64_t piece_bytes = 0;    ///< bytes of piece data handed to the GPU
};

}  // namespace far
