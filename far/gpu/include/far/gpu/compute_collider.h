#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "far/base/result.h"
#include "far/model/contact_pair.h"
#include "far/model/mesh.h"

namespace far {

/// A node of a hierarchy's topology (TriangleBvh's, without its boxes): a leaf when count > 0,
/// holding the triangles order[first, first + count), else an inner node whose children are
/// nodes first and first + 1. Node 0 is the root; every node's triangles are a contiguous range
/// of the order.
struct ComputeNode {
  uint32_t first = 0;
  uint32_t count = 0;
};

/// One object of a GPU step, by slot (an empty one: a free slot). Aliased: the spans must live
/// until Run returns.
struct ComputeObject {
  std::span<const Eigen::Vector3d> p_WV;  ///< world vertices, what the exact predicates read
  std::span<const TriangleIndices> triangles;
  std::span<const ComputeNode> nodes;  ///< the hierarchy's topology over `triangles`
  std::span<const uint32_t> order;     ///< triangle indices in leaf order
  /// Changes whenever triangles, nodes or order change (a new object in the slot).
  uint64_t topology_key = 0;
  /// Changes whenever p_WV changes.
  uint64_t world_key = 0;
  /// The object's world box as sweep-and-prune grows it (SweepAndPrune::GrownBox): two objects
  /// whose pair boxes overlap, closed, on every axis are an object pair. Empty or not finite:
  /// the object pairs with nothing.
  Eigen::AlignedBox3d pair_box;
  /// A posed object (not at the identity pose): its own vertices and pose, with p_WV[v] ==
  /// WorldVertex(X_WM, p_MV[v]) (far/model/world_vertex.h). The collider then uploads p_MV
  /// once (until model_key changes) and X_WM when the world changed, and places the vertices
  /// on the GPU, where the device computes those same doubles (PlacesOnGpu). Empty p_MV: p_WV
  /// is uploaded whenever it changed.
  std::span<const Eigen::Vector3d> p_MV = {};
  Eigen::Matrix<double, 3, 4> X_WM = Eigen::Matrix<double, 3, 4>::Zero();
  /// Changes whenever p_MV changes (0: no p_MV).
  uint64_t model_key = 0;
};

/// What a GPU step is asked: the object pairs whose pair boxes meet, and the triangle pairs of
/// those whose boxes meet.
struct ComputeQuery {
  std::span<const ComputeObject> objects;  ///< by slot
  /// Triangle boxes within this of each other on every axis meet (0: they share a point).
  double slack = 0;
  /// A distance query: every pair whose boxes meet is kept (for the CPU's distance), not only
  /// those the filters cannot prove apart...
  bool distance = false;
  /// ...except the pairs proven farther than TriangleDistanceIfWithin(s, t, max_distance) would
  /// ever accept (the CPU's own lower bounds, in fp64 with their rounding: docs/culling.md).
  /// +infinity: none is dropped.
  double max_distance = std::numeric_limits<double>::infinity();
};

/// The GPU step's answer: object pairs sorted, triangle pairs unsorted.
struct ComputeAnswer {
  /// The object pairs (object_a < object_b), sorted: those SweepAndPrune::Update reports for
  /// the same boxes.
  std::vector<SlotPair> object_pairs;
  /// Pairs the filters proved to intersect (exactly the exact predicates' answer for them).
  std::vector<SlotContact> crossing;
  /// Pairs left to the CPU's exact predicates: not proven apart or crossing (a contact query),
  /// or every other pair whose boxes meet (a distance query).
  std::vector<SlotContact> undecided;
  /// Indexed like `undecided`: 1 where the filters proved the pair apart (a distance query's
  /// pair that needs only its distance).
  std::vector<uint8_t> proven_apart;
  /// By slot (indexed like ComputeQuery::objects), sorted: the triangles in some crossing or
  /// undecided pair, the primitive PCS.
  std::vector<std::vector<uint32_t>> pcs;
  int64_t box_pairs = 0;        ///< triangle pairs whose boxes met
  int64_t float_decided = 0;    ///< of those, decided by the float filter
  int64_t double_decided = 0;   ///< decided by the fp64 filter (the float one could not)
  int64_t distance_culled = 0;  ///< a distance query's pairs dropped by max_distance
  int64_t bytes_uploaded = 0;
  /// World vertices of posed objects placed on the GPU from their pose, not uploaded.
  int64_t vertices_placed = 0;
  int runs = 1;  ///< traversals run: more than one when the output buffers had to grow
  // Where the time went (milliseconds). CPU: issuing the uploads and kernels, then waiting for
  // the GPU and reading the pairs back (cpu_read_ms of it: the reading). GPU (timer queries):
  // the uploads with the placement, boxes and refit; the (last run's) object pairs and
  // traversal; its filters.
  double cpu_submit_ms = 0, cpu_wait_ms = 0, cpu_read_ms = 0;
  double gpu_refit_ms = 0, gpu_traverse_ms = 0, gpu_filter_ms = 0;
};

/// The GPU-resident part of the `gpu` method, in compute shaders of the current OpenGL 4.5
/// context: each step uploads the world vertices of the objects that moved, or the pose of a
/// posed one whose own vertices are on the GPU already (and, when the set
/// of objects changed, their triangles and hierarchy topologies) and every object's box,
/// computes every triangle's box, refits every hierarchy, finds the object pairs, descends each
/// object pair's hierarchies, and classifies the triangle pairs whose boxes meet (one per
/// invocation) with a float filter and then an fp64 filter, both with proven error bounds
/// (docs/culling.md). The pairs are compacted on the GPU and read back
/// once. Never drops a pair the exact predicates would accept.
/// Threading: far::GlContext's contract; Run takes far::LockGl for its GL work.
class ComputeCollider {
 public:
  /// Compiles the kernels. @pre an OpenGL 4.5 context is current. Errors: kInternal with the
  /// driver's log.
  static Result<std::unique_ptr<ComputeCollider>> Create();
  ~ComputeCollider();
  ComputeCollider(const ComputeCollider&) = delete;
  ComputeCollider& operator=(const ComputeCollider&) = delete;

  /// Runs one step. Errors: kUnavailable when a hierarchy is too deep for the traversal's
  /// stack or the work is over the kernels' 32-bit counts; kLimitExceeded for more object
  /// pairs or triangle pairs whose boxes meet than its limits; kInternal for a GL error.
  Result<ComputeAnswer> Run(const ComputeQuery& query);

  /// Run in two halves, for a caller that puts several colliders' steps on the GPU together
  /// (far::ComputeBatcher): Submit issues the step's uploads and kernels and returns at once,
  /// Finish waits for them and reads the answer back. Between the two the query's spans must
  /// live, and other colliders of the same context may submit theirs. @pre the caller holds the
  /// GL lock (far::LockGl) across both. Errors: as Run's; Finish fails with kInternal when no
  /// Submit came first.
  Result<void> Submit(const ComputeQuery& query);
  /// Whether the submitted step's GPU work is done, so that Finish would not wait (true when
  /// none was submitted). A step's fence follows its last command: another collider's step
  /// submitted after it does not delay it. @pre the caller holds the GL lock.
  bool Ready() const;
  Result<ComputeAnswer> Finish();

  /// Whether posed objects are placed on the GPU: Create ran the placement kernel on probe
  /// vertices and poses (magnitudes from 2^-260 to 1e12, sums that cancel) and it gave
  /// WorldVertex's doubles for every one. False on a device that fuses or reorders them
  /// despite `precise`: every world vertex is then uploaded, as computed on the CPU.
  bool PlacesOnGpu() const;

  /// Depth limit of a hierarchy the traversal can descend (root at depth 0).
  static int MaxDepth();

 private:
  struct Impl;
  explicit ComputeCollider(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace far
