#pragma once

// Bounds on the screen area a piece may cover in any axis view, whatever its pose: what a view's
// batch of draws may cost a rasterizer that pays per fragment (llvmpipe), known before the batch
// is drawn (draw_pacer.h). Private to far::gpu.

#include <cstdint>

#include "far/gpu/culling_renderer.h"

namespace far::internal {

/// A piece's drawn shape grown by the view's radius R projects to at most
/// area + R * linear + n * grown * R^2 (world units^2; n = 1 per piece), in any direction. Sums
/// of pieces add up.
struct PieceFootprint {
  double area = 0;    ///< the projection's area bound at R = 0
  double linear = 0;  ///< the bound's growth per unit of R (also bounds the perimeter)
  double grown = 0;   ///< the bound's growth per R^2

  PieceFootprint& operator+=(const PieceFootprint& o) {
    area += o.area;
    linear += o.linear;
    grown += o.grown;
    return *this;
  }
  PieceFootprint operator-(const PieceFootprint& o) const {
    return {area - o.area, linear - o.linear, grown - o.grown};
  }
};

/// The footprint of one instance of `set` (PieceInstance's layout per set).
PieceFootprint FootprintOf(PieceSet set, const PieceInstance& piece);

/// A view's scale: pixels a run of `count` pieces with footprint `sum` may cover, counting a
/// pixel of fringe around each piece, and no piece more than the whole viewport.
struct ViewScale {
  double px_per_unit = 0;  ///< the larger of the two screen axes' scales
  double radius = 0;       ///< the largest radius the view grows its pieces by, world units
  double view_pixels = 0;  ///< width * height

  double Pixels(const PieceFootprint& sum, uint64_t count) const;
};

}  // namespace far::internal
