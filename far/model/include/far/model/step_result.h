#pragma once

// What one step answers and what it cost: the reply of far::Pipeline::Step, of the daemon and
// of far::client::Client::Step alike.

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "far/base/stage.h"
#include "far/model/contact_geometry.h"
#include "far/model/contact_pair.h"

namespace far {

/// Time and work of one stage of a step.
struct StageStats {
  Stage stage = Stage::kUpdate;
  double ms = 0;
};

/// The numbers one GPU culling level used, largest over its views: together they say why no
/// primitive that could touch another was culled (docs/bounding-offsets.md). A primitive is
/// fattened by offset_radius, which covers the pixel and depth steps of the view (pixel_size,
/// depth_step) and the float32 rounding of the vertices the GPU draws (rounding, included in
/// offset_radius), over the world bounds of the level's primitives.
struct LevelCertificate {
  std::string level;  ///< "object" or "sub-object"
  int views = 0;      ///< orthographic views rendered
  int resolution = 0;
  double offset_radius = 0;
  double pixel_size = 0;
  double depth_step = 0;
  double rounding = 0;
  std::array<double, 3> world_min{}, world_max{};
};

/// Whether a step's answer is guaranteed to hold every contact (and distance pair), and why.
struct Certificate {
  bool guaranteed = false;
  std::string basis;                     ///< why (or why not), in words
  std::vector<LevelCertificate> levels;  ///< the GPU methods' culling levels; empty for CPU ones
};

/// The work of the bvh method's descent (RunBvhTests), for profiling what a step's time goes to
/// (far-step-profile prints it). The same for any number of threads: the descent visits the same
/// node pairs, only in another order.
struct DescentCounters {
  int64_t node_pairs = 0;          ///< pairs of inner nodes split into their children
  int64_t leaf_descents = 0;       ///< leaves sent down the other object's hierarchy
  int64_t leaf_descent_nodes = 0;  ///< nodes of the other hierarchy those descents visited
  int64_t leaf_pairs = 0;          ///< leaf pairs whose live triangles were paired up
  int64_t boxes_met = 0;  ///< of those triangle pairs, the ones whose world boxes met (then slabs)

  DescentCounters& operator+=(const DescentCounters& other) {
    node_pairs += other.node_pairs;
    leaf_descents += other.leaf_descents;
    leaf_descent_nodes += other.leaf_descent_nodes;
    leaf_pairs += other.leaf_pairs;
    boxes_met += other.boxes_met;
    return *this;
  }
  bool operator==(const DescentCounters&) const = default;
};

/// What the gpu method's filters did (zero for other methods).
struct GpuFilterCounters {
  int64_t box_pairs = 0;       ///< triangle pairs whose boxes met (the filters' input)
  int64_t float_decided = 0;   ///< of those, decided by the float filter
  int64_t double_decided = 0;  ///< decided by the fp64 filter (the float one could not)
  int64_t sent_to_cpu = 0;     ///< pairs left to the CPU's exact predicates
  /// A distance query's pairs within the slack that the GPU proved farther than D (with the
  /// CPU's rounding): not sent to the CPU.
  int64_t distance_culled = 0;
  int traversals = 0;  ///< GPU traversals run (more than 1: its buffers grew)
  /// Deformable objects whose hierarchy topology was rebuilt, refitting having made it loose.
  int topologies_rebuilt = 0;
  /// World vertices of posed objects placed on the GPU from their poses (not uploaded).
  int64_t vertices_placed = 0;
  double gpu_refit_ms = 0;     ///< GPU time of the uploads, triangle boxes and refit
  double gpu_traverse_ms = 0;  ///< GPU time of the object pairs and the traversal
  double gpu_filter_ms = 0;    ///< GPU time of the float and fp64 filters
  bool operator==(const GpuFilterCounters&) const = default;
};

/// What a step did and cost.
struct StepStats {
  /// The configuration that ran: the method's name, and for the GPU methods the mechanism and
  /// resolution ("bvh", "far/id-buffer/256"). Under auto, the one it chose.
  std::string method;
  /// Why auto chose it (measured and predicted costs); empty for other methods.
  std::string method_reason;
  std::vector<StageStats> stages;
  double total_ms = 0;
  int64_t primitives_rendered = 0;  ///< object and sub-object primitives drawn, all views
  int64_t draws = 0;
  int64_t queries = 0;
  /// Pauses between batches of the GL views' draws, a glFinish each (src/draw_pacer.h): made
  /// only while the step can stop or another thread waits for the GL lock.
  int64_t gl_pauses = 0;
  int64_t bytes_uploaded = 0;  ///< to the GPU this step
  /// The GPU methods' culling views, all of them: CPU time preparing them (uploads, draw
  /// commands), CPU time in their passes (issuing the GL calls, waiting for and reading back
  /// the results), and the GPU's own time for those passes (GL timer queries). The rest of the
  /// culling stages is CPU work around the views. Not sent over the wire (study measurements).
  double gl_prepare_ms = 0;
  double gl_passes_ms = 0;
  double gl_gpu_ms = 0;
  /// Candidate object pairs after sweep-and-prune. fcl: the pairs its broadphase passed to
  /// collide; exact: the pairs in its answer (it has no candidates).
  int64_t object_pairs = 0;
  /// Candidate triangle pairs (PCS x PCS over object pairs). fcl: n_a * n_b summed over its
  /// broadphase pairs; exact: every cross-object pair.
  int64_t pairs_considered = 0;
  /// Triangle pairs that reached an exact test. fcl: the pairs that reached FCL's own triangle
  /// test, those whose leaf boxes overlapped in its BVH traversal (its num_leaf_tests); exact:
  /// the pairs that passed the triangle-box prefilter.
  int64_t pairs_tested = 0;
  /// bvh: the descent's work (zero for other methods). Not sent over the wire (study
  /// measurements).
  DescentCounters descent;
  /// gpu: its filters' work (zero for other methods). Not sent over the wire.
  GpuFilterCounters gpu_filter;
  double object_radius = 0;     ///< offset radius r of the last object-level view
  double primitive_radius = 0;  ///< offset radius r of the last sub-object view
  Certificate certificate;
};

/// The answer of one step. Ids and triangle indices are as in the scene (docs/scene-format.md).
struct StepResult {
  std::vector<uint32_t> pcs_objects;                         ///< sorted ids
  std::vector<ObjectPair> object_pairs;                      ///< sorted, object_a < object_b
  std::map<uint32_t, std::vector<uint32_t>> pcs_primitives;  ///< id -> sorted triangles
  std::vector<ContactPair> contacts;                         ///< sorted
  std::vector<DistancePair> distance_pairs;                  ///< sorted
  /// Only when StepRequest::geometry asked (else empty): contact_geometry[i] for contacts[i],
  /// closest_points[i] for distance_pairs[i], and one Penetration per object pair that has a
  /// contact, sorted by (object_a, object_b).
  std::vector<ContactGeometry> contact_geometry;
  std::vector<ClosestPoints> closest_points;
  std::vector<Penetration> penetrations;
  StepStats stats;
};

}  // namespace far
