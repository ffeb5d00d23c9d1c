#include "guarantee.h"

namespace far::internal {
namespace {

// What "touching" means for the request: contact, or within the distance D.
std::string Within(const StepRequest& request) {
  return request.distance ? "within D = " + std::to_string(*request.distance) : "touching";
}

}  // namespace

std::string GuaranteeBasis(const StepRequest& request) {
  const std::string within = Within(request);
  switch (request.method) {
    case Method::kExact:
      return "guaranteed: every triangle pair of different objects went through the exact "
             "predicates (the brute-force reference)";
    case Method::kBvh:
      return "guaranteed: exact predicates on every triangle pair whose hierarchy boxes "
             "overlap; the boxes hold the triangles exactly and are compared with a margin "
             "covering the rounding of the world vertices, so no pair " +
             within + " is pruned";
    case Method::kAabb:
      return "guaranteed: exact predicates on every pair of triangles whose world boxes meet "
             "the partner object's box grown by D; the boxes are taken over the same world "
             "vertices the predicates test, so no pair " +
             within + " is pruned";
    case Method::kGpu:
      return "guaranteed: every triangle pair whose boxes (rounded outward to float, with the "
             "hierarchies refit from them) meet is decided from orientation signs only where "
             "the float or fp64 filter's proven error bound certifies them, and by the CPU's "
             "exact predicates otherwise, so no pair " +
             within + " is pruned (docs/culling.md, 'The gpu method')";
    case Method::kFar:
    case Method::kFarExactOffset:
      return std::string(
                 "guaranteed: the hierarchies (as in bvh) keep every triangle near a "
                 "partner; at each GPU level below every primitive was drawn in ") +
             (request.method == Method::kFar ? "its UOBB" : "its bounded exact offset") +
             " of radius r >= D/2 + sqrt(3) max(pixel size, depth step) + float32 rounding, "
             "so a primitive " +
             within +
             " of another stays visible in a view and is kept; survivors went "
             "through the exact predicates";
    case Method::kCullide:
      return "not guaranteed: cullide draws the triangles themselves (offset radius 0), so "
             "features thinner than a pixel can be culled although they touch";
    case Method::kFcl:
      return "not guaranteed: FCL's own floating-point triangle test misses touching, "
             "coplanar and degenerate pairs (bench/RESULTS.md)";
    case Method::kAuto:
      break;
  }
  return "not guaranteed: no concrete method ran";
}

}  // namespace far::internal
