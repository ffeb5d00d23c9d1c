#pragma once

#include <cstdint>
#include <optional>

namespace far {

/// What `auto` predicts a GPU step's time from, on one renderer: fixed + per_triangle *
/// triangles (milliseconds), for the raster FAR configurations and, when it was measured, for
/// the gpu method (compute shaders). Measured by MeasureGpuCost (pipeline.h).
struct GpuCost {
  double fixed_ms = 0;
  double ms_per_triangle = 0;
  std::optional<double> compute_fixed_ms = std::nullopt;
  std::optional<double> compute_ms_per_triangle = std::nullopt;
  double Predict(int64_t triangles) const {
    return fixed_ms + ms_per_triangle * static_cast<double>(triangles);
  }
  std::optional<double> PredictCompute(int64_t triangles) const {
    if (!compute_fixed_ms || !compute_ms_per_triangle) return std::nullopt;
    return *compute_fixed_ms + *compute_ms_per_triangle * static_cast<double>(triangles);
  }
  bool operator==(const GpuCost&) const = default;
};

}  // namespace far
