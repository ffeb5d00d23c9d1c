#pragma once

// The compute shaders of the GPU-resident step (ComputeCollider, compute_collider.h): triangle
// boxes, hierarchy refit, object pairs, the traversal, and the float and fp64 filters. Their error
// bounds are argued in docs/culling.md, "The gpu method's filters"; the constants here are the ones
// proven there.

#include <string>

namespace far::internal {

/// Shader storage bindings shared by the kernels.
enum ComputeBinding : int {
  kPositionsBinding = 0,     // double[3 * vertices]: world vertices, every object one after another
  kTrianglesBinding = 1,     // uint[3 * triangles]: global vertex indices
  kTriBoxesBinding = 2,      // vec4[2 * triangles]: lo, hi (float, rounded outward), in leaf order
  kNodesBinding = 3,         // uvec4[nodes]: first child, leaf count, order range [lo, hi)
  kOrderBinding = 4,         // uint[triangles]: global triangle ids in leaf order
  kNodeBoxesBinding = 5,     // vec4[2 * nodes]: lo, hi
  kWorkBinding = 6,          // uvec4[2 * pairs]: per object pair, see kTraverse
  kWorkStartBinding = 7,     // uint[pairs + 1]: prefix sums of the driver triangles
  kCountersBinding = 8,      // uint[kNumCounters]
  kCrossingBinding = 9,      // uvec4[capacity]: certified intersecting pairs
  kUndecidedBinding = 10,    // uvec4[capacity]: pairs for the CPU's exact predicates
  kRangesBinding = 11,       // uvec2[ranges]: the moved objects' triangles (first, before)
  kRefitListBinding = 12,    // uint[]: the moved objects' nodes, level by level, deepest first
  kPcsBitsBinding = 13,      // uint[]: a bit per global triangle, set when a kept pair holds it
  kPairBoxesBinding = 14,    // double[8 * boxes]: pair boxes by low x (lo, slot, hi, 0)
  kSlotsBinding = 15,        // uvec4[slots]: first triangle, triangles, root node, nodes
  kObjectPairsBinding = 16,  // uvec2[pair capacity]: the object pairs found (slot < slot)
  kDispatchBinding = 17,     // uint[kNumDispatchWords]: the traversal's and filters' dispatches
  kCandidatesBinding = 18,   // uvec4[candidate capacity]: triangle pairs whose boxes meet
  kModelBinding = 19,        // double[3 * vertices]: posed objects' own vertices p_MV, as positions
  kPlacementsBinding = 20,  // double[16 * placements]: X_WM row by row, first vertex, count, before
  kNumBindings = 21,
};

/// The counters the kernels write (kCountersBinding).
enum ComputeCounter : int {
  kCrossingCount = 0,    // certified intersecting pairs written (may exceed the capacity)
  kUndecidedCount = 1,   // pairs for the CPU written (may exceed the capacity)
  kBoxPairs = 2,         // triangle pairs whose boxes met (may exceed the candidate capacity)
  kFloatDecided = 3,     // of those, decided by the float filter
  kDoubleDecided = 4,    // decided by the fp64 filter
  kStackOverflow = 5,    // nonzero: a traversal ran out of stack (never expected: depth checked)
  kDistanceCulled = 6,   // a distance query's pairs proven farther than the CPU would accept
  kObjectPairCount = 7,  // object pairs found (may exceed the pair capacity)
  kWorkOverflow = 8,     // nonzero: 2^32 or more driver triangles to descend
  kNumCounters = 9,
};

/// The words of kDispatchBinding: the traversal's work groups (x, y, z, as
/// glDispatchComputeIndirect reads them), its driver triangles and object pairs, then the
/// filters' work groups and candidates.
enum DispatchWord : int {
  kGroupsX = 0,
  kTraverseItems = 3,
  kTraversePairs = 4,
  kFilterGroupsX = 5,
  kFilterItems = 8,
  kNumDispatchWords = 9,
};

/// Threads per work group of every kernel.
inline constexpr int kComputeGroupSize = 64;
/// Entries of a traversal's stack: hierarchies deeper than this minus one are refused.
inline constexpr int kTraversalStack = 64;

/// One box per invocation, sweeping the boxes sorted after it: the object pairs whose boxes
/// (kPairBoxesBinding) meet.
std::string ObjectPairsSource();
/// One work group: each object pair's traversal work (its driver, the smaller object, whose
/// triangles descend the other's hierarchy), their prefix sums and the traversal's dispatch.
std::string PairWorkSource();
/// One vertex of a posed object that moved per invocation: its world position from its own
/// (kModelBinding) and the object's pose (kPlacementsBinding), the doubles far::WorldVertex
/// computes (each product and sum rounded once, in its order: `precise`).
std::string PlaceSource();
/// One triangle of a moved object per invocation: its world box from its double corners,
/// rounded outward to float.
std::string TriangleBoxesSource();
/// One node of one level per invocation: the union of its triangles' or its children's boxes.
std::string RefitSource();
/// One driver triangle of one object pair per invocation: descends the partner's hierarchy and
/// appends each triangle pair whose boxes meet to the candidates (kCandidatesBinding).
std::string TraverseSource();
/// One invocation: the filters' dispatch, a work group per 64 candidates.
std::string FilterDispatchSource();
/// One candidate per invocation: classified with the float filter, then the fp64 filter; the
/// certified intersecting pairs and the undecided ones are appended. `distance`: the distance
/// queries' kernel (the pairs proven apart go to the CPU too, but for those proven farther than
/// it would accept); a separate program, so that the contact queries' kernel carries none of
/// that code (on llvmpipe it slowed theirs by 12-50%).
std::string FilterSource(bool distance);

}  // namespace far::internal
