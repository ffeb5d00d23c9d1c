#pragma once

#include <optional>
#include <string>

#include "far/pipeline/internal/auto_selector.h"

namespace far::internal {

/// The cost of a FAR step and of a gpu step (compute shaders) on the renderer of the GL context
/// current on this thread, each as a fixed
/// part and a part per triangle: measured once per renderer and process (far, id-buffer, 256^2,
/// contacts, on two fixed scenes of overlapping objects, 1,080 and 3,888 triangles) and cached.
/// What auto predicts GPU steps from. nullopt when no context is current or the probe fails.
/// Thread-safe (the cache is locked); the measurement runs on the calling thread.
std::optional<GpuCost> ProbeGpuCost();

/// Makes `cost` the cached cost of the current context's renderer, as if ProbeGpuCost had
/// measured it. False when no context is current.
bool AdoptGpuCost(const GpuCost& cost);

}  // namespace far::internal
