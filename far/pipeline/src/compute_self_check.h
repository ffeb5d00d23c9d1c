#pragma once

#include <string>

#include "far/base/result.h"
#include "far/gpu/compute_collider.h"

namespace far::internal {

/// Holds a ComputeCollider on this context's driver to the exact predicates before the gpu
/// method trusts it: about 5,000 single-triangle pairs chosen to stress the filters (general
/// position, a double step from touching at the origin and 1e6 away, slivers, triangles too
/// small for the float filter) and a few meshes with hierarchies descended by the traversal
/// (every intersecting pair found, none twice), and 1,400 pairs around a distance query's D (none
/// that the CPU's distance test accepts dropped by the distance cut). The filters' bounds assume
/// IEEE arithmetic and a compiler that keeps the evaluation order (docs/culling.md); a driver that
/// breaks either fails here instead of answering wrongly. Returns kUnavailable naming the first
/// disagreement.
/// @pre a GL context is current (the collider's).
Result<void> SelfCheckComputeCollider(ComputeCollider& collider);

}  // namespace far::internal
