// The offset radius r and the projection bounds of one culling pass.
//
// Derivation (docs/bounding-offsets.md has the same with pictures).
//
// 1. Resolution per world axis. The pass renders three orthographic views into one
//    width x height viewport: along X (screen axes Y, Z), along Y (screen Z, X) and along Z
//    (screen X, Y), with depth resolution RES(Z) = DepthResolution(format). Every world axis A
//    is the horizontal screen axis of one view, the vertical one of another and the depth axis
//    of the third, so its worst cell is d_A = E'_A / RES with RES = min(width, height, RES(Z))
//    and E'_A the extent of the projection bounds along A.
//
// 2. Theorem 1 with distance culling: r = D/2 + sqrt(3) p / 2, p = max_A 2 d_A, that is
//    r = D/2 + sqrt(3) max_A E'_A / RES.
//
// 3. The bounds depend on r. A UOBB corner is a rectangle point plus r (+-u +-v +-n); along A
//    that is at most r (|u_A| + |v_A| + |n_A|) <= r sqrt(3) (a row of an orthonormal matrix
//    has unit length, and the 1-norm of a unit 3-vector is at most sqrt(3)). The bounded exact
//    offset's edge boxes are an edge point plus rho (+-e +-w +-n), its prism a triangle point
//    plus t n, with rho, t <= r (1 + 2^-24) + (a few units of roundoff): the same bound up to
//    a margin far below the one added in step 5. So E'_A = E_A + 2 g with g = sqrt(3) r + m,
//    E_A the extent of rect_bounds_W, m a margin (step 5).
//
// 4. The GPU sees float32. Coordinates are taken relative to center_W in double and then
//    rounded to float32; a vertex shader may also build corners from center, axes and half
//    extents, and the projection and viewport transforms round again. Counting in units of
//    U = 2^-24 (H + r), H the largest half extent of the bounds (no local coordinate, half
//    extent or partial sum exceeds a small multiple of H + r): conversion 1, corner
//    construction (axes and half extents rounded, three products, three sums) <= 11,
//    orthographic scale and its product 2, viewport or depth mapping 4: 18 U. We take
//    eps = kGpuRoundings U per coordinate with kGpuRoundings = 32. A rendered vertex may sit
//    sqrt(3) eps (Euclidean) from its exact place, and every rendered point (an interpolation
//    of vertices) likewise; by a winding-number argument the rendered closed surface then
//    still encloses every point deeper than sqrt(3) eps inside the exact one. So r grows by
//    sqrt(3) eps. (Rounding in double on the CPU is covered where the boxes are built: every
//    half extent carries 32 units of roundoff of the coordinates' magnitude.)
//
// 5. Margin. The bounds must strictly contain every rendered vertex, so that nothing is
//    clipped on a near or far plane or lands on a viewport edge: m = 2 eps + psi, with
//    psi = kCpuRoundings 2^-53 M (M the largest |coordinate| of rect_bounds_W) for what double
//    precision adds at the scene's absolute position: the boxes' own slack s (32 units of
//    2^-53 M: an edge box reaches up to sqrt(3) (rho + s) <= sqrt(3) (r + 3 s) from a vertex,
//    which its rectangle covers to s, so up to 4.2 s = 134 units beyond sqrt(3) r), the
//    rounding of corners, of rect_bounds_W and of the bounds themselves (< 16 units): 150
//    units, kCpuRoundings = 256. psi also keeps degenerate bounds (a single point) from
//    collapsing: g >= psi > ulp(M).
//
// 6. Closed form. With H = E_max / 2 + g and everything linear in r:
//      eps = phi (H + r),  phi = kGpuRoundings 2^-24
//          = phi (E_max/2 + psi + (1 + sqrt 3) r + 2 eps)
//       => eps = eps0 + eps1 r, eps0 = phi (E_max/2 + psi) / (1 - 2 phi),
//                               eps1 = phi (1 + sqrt 3) / (1 - 2 phi);
//      r = D/2 + sqrt 3 (E_max + 2 g) / RES + sqrt 3 eps,  2 g = 2 sqrt 3 r + 4 eps + 2 psi
//        = D/2 + sqrt 3 (E_max + 2 psi) / RES + 6 r / RES + sqrt 3 (1 + 4 / RES) eps
//       => r = [D/2 + sqrt 3 (E_max + 2 psi) / RES + sqrt 3 (1 + 4/RES) eps0]
//              / [1 - 6 / RES - sqrt 3 (1 + 4/RES) eps1].
//    The denominator is positive iff RES > 6 (plus a hair): with fewer pixels, growing r grows
//    the bounds faster than it covers them, and no r works. We demand RES >= 8.
//    Any larger r satisfies the inequality too (it reads r >= alpha + beta r with beta < 1),
//    so rounding r up is safe. The computed bounds are then checked against the inequality as
//    a caller would evaluate it (from the returned bounds, in double) and r is raised if the
//    last rounding fell short; the shortfall shrinks by 6 / RES per round.
//
// 7. Floors. r >= 2^-64 keeps float32 local coordinates normal and the orthographic scale
//    2 / E' finite even when every primitive is one point at the origin (E = D = M = 0).
//    Elsewhere a degenerate scene needs no special case: psi > 0 gives g > 0 and r > 0.

#include "far/offsets/bounding_offset.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "triangle_frame.h"

namespace far {
namespace {

constexpr double kSqrt3 = 1.7320508075688772935;
constexpr double kGpuRoundings = 32;        // float32 roundings per coordinate, in U (step 4)
constexpr double kCpuRoundings = 256;       // double roundings per coordinate, in 2^-53 M (step 5)
constexpr double kMinRadius = 0x1p-64;      // step 7
constexpr double kMaxCoordinate = 0x1p100;  // float32 (max ~2^128) with headroom for products
constexpr int kMinViewport = 8;             // step 6: RES > 6

// Throws std::invalid_argument: a violated precondition of our own callers (FAR_DEMAND tier).
void Demand(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument("ComputeProjection: " + message);
}

// Returns the projection for radius r (steps 3 and 5).
Projection BuildProjection(const Eigen::AlignedBox3d& rect_bounds_W, double r, double eps0,
                           double eps1, double psi) {
  const double eps = eps0 + eps1 * r;
  const double grow = internal::RoundUp(kSqrt3 * r + 2 * eps + psi);
  Projection projection;
  projection.radius = r;
  projection.bounds_W =
      Eigen::AlignedBox3d(rect_bounds_W.min().array() - grow, rect_bounds_W.max().array() + grow);
  projection.center_W = projection.bounds_W.center();
  return projection;
}

// Fills in the pixel size, depth step and rounding bound of the projection as computed (steps
// 2 and 4) and returns the radius they need.
double RequiredRadius(Projection& projection, const RasterFormat& raster, double distance,
                      double phi) {
  const double extent = projection.bounds_W.sizes().maxCoeff();
  projection.pixel_size = extent / std::min(raster.width, raster.height);
  projection.depth_step = extent / DepthResolution(raster.depth);
  projection.rounding = kSqrt3 * phi * (0.5 * extent + projection.radius);
  return 0.5 * distance + kSqrt3 * std::max(projection.pixel_size, projection.depth_step) +
         projection.rounding;
}

}  // namespace

double DepthResolution(DepthFormat format) {
  switch (format) {
    case DepthFormat::kDepth16:
      return 0x1p16 - 1;  // unsigned normalized: steps 1/(2^16 - 1)
    case DepthFormat::kDepth24:
      return 0x1p24 - 1;
    case DepthFormat::kDepth32F:
      return 0x1p24;  // float steps in [1/2, 1) are 2^-24
  }
  return 0x1p16 - 1;  // not reached; the coarsest format is the safe answer
}

Projection ComputeProjection(const Eigen::AlignedBox3d& rect_bounds_W, const RasterFormat& raster,
                             double distance) {
  // Preconditions: these are our own callers' invariants, not client data.
  Demand(rect_bounds_W.min().allFinite() && rect_bounds_W.max().allFinite(),
         "rect_bounds_W is not finite");
  Demand(!rect_bounds_W.isEmpty(), "rect_bounds_W is empty");
  const double magnitude = std::max(rect_bounds_W.min().cwiseAbs().maxCoeff(),
                                    rect_bounds_W.max().cwiseAbs().maxCoeff());
  Demand(magnitude <= kMaxCoordinate,
         "rect_bounds_W reaches " + std::to_string(magnitude) + ", beyond 2^100");
  Demand(std::isfinite(distance) && distance >= 0 && distance <= kMaxCoordinate,
         "distance " + std::to_string(distance) + " is not in [0, 2^100]");
  Demand(raster.width >= kMinViewport && raster.height >= kMinViewport,
         "raster " + std::to_string(raster.width) + "x" + std::to_string(raster.height) +
             " is below 8x8, where no offset radius makes the views conservative");

  // Step 1: one resolution for every axis.
  const double res = std::min({static_cast<double>(raster.width),
                               static_cast<double>(raster.height), DepthResolution(raster.depth)});
  // Step 6: the closed form.
  const double e_max = rect_bounds_W.sizes().maxCoeff();
  const double phi = kGpuRoundings * 0x1p-24;
  const double psi = kCpuRoundings * internal::kDoubleUnit * magnitude;
  const double eps0 = phi * (0.5 * e_max + psi) / (1 - 2 * phi);
  const double eps1 = phi * (1 + kSqrt3) / (1 - 2 * phi);
  const double growth = kSqrt3 * (1 + 4 / res);
  const double numerator = 0.5 * distance + kSqrt3 * (e_max + 2 * psi) / res + growth * eps0;
  const double denominator = 1 - 6 / res - growth * eps1;
  double r = std::max(internal::RoundUp(numerator / denominator), kMinRadius);

  // Check the rounded result the way a caller would, and raise r where rounding fell short.
  for (int round = 0;; ++round) {
    Projection projection = BuildProjection(rect_bounds_W, r, eps0, eps1, psi);
    const double required = RequiredRadius(projection, raster, distance, phi);
    if (r >= required) return projection;
    Demand(round < 8, "radius did not converge (r " + std::to_string(r) + ", required " +
                          std::to_string(required) + ")");
    r = internal::RoundUp(required);
  }
}

}  // namespace far
