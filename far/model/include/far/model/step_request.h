#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "far/base/result.h"
namespace far {

/// Depth buffer formats a culling pass can render with.
enum class DepthFormat { kDepth16, kDepth24, kDepth32F };

/// How a step finds its potentially colliding set.
enum class Method {
  kAabb,            ///< CPU sweep-and-prune on object AABBs only (I-COLLIDE baseline)
  kBvh,             ///< CPU: object sweep-and-prune, then per-object hierarchies (TriangleBvh)
  kCullide,         ///< CULLIDE: unfattened primitives on the GPU; can miss (not reliable)
  kFar,             ///< FAR with UOBB bounding offsets: reliable
  kFarExactOffset,  ///< FAR with bounded exact offsets: reliable, tighter, more vertices
  kFcl,             ///< FCL dynamic AABB tree broadphase + BVHModel<OBBRSS> collide
  kExact,           ///< brute-force exact reference (every cross-object triangle pair)
  /// GPU-resident exact step in compute shaders: hierarchies refit and descended on the GPU,
  /// triangle pairs decided by float and fp64 filters with proven bounds, the rest by the
  /// CPU's exact predicates. Reliable; needs a GL 4.5 context (docs/culling.md).
  kGpu,
  /// The fastest reliable method for this renderer and scene, chosen per step from measured
  /// costs (never cullide, fcl or exact); the result's stats name what ran and why.
  kAuto,
};

/// How the GPU answers "is this primitive fully visible against the other objects".
enum class QueryMechanism {
  kOcclusionQuery,  ///< per-primitive occlusion queries, two passes (the paper)
  kIdBuffer,        ///< a fixed number of draws per axis with an object-id buffer (docs/culling.md)
};

/// The deepest output a step computes; later stages do not run.
enum class Output {
  kObjectPcs,      ///< objects that may collide
  kObjectPairs,    ///< candidate object pairs (sweep-and-prune on the PCS objects)
  kPrimitivePcs,   ///< per object, the triangles that may collide
  kContacts,       ///< exact intersecting triangle pairs
  kDistancePairs,  ///< exact triangle pairs within the distance D (requires distance)
};

/// What one step computes and how.
struct StepRequest {
  Method method = Method::kAuto;
  /// The GPU methods' mechanism and viewport; auto chooses its own.
  QueryMechanism mechanism = QueryMechanism::kIdBuffer;
  int resolution = 1024;  ///< viewport is resolution x resolution
  DepthFormat depth_format = DepthFormat::kDepth24;
  int subobject_size = 1;          ///< triangles per sub-object (k)
  std::optional<double> distance;  ///< D for localized distance culling (world units)
  Output output = Output::kContacts;
  /// Also compute the contact geometry (far/model/contact_geometry.h): for every contact the
  /// points where its triangles meet and their normals, for every distance pair its closest
  /// points, for every object pair in contact its penetration depth. Runs as the "geometry"
  /// stage after the exact one; nothing of it runs when false. Needs output contacts or distance.
  bool geometry = false;
};

/// Names used on command lines and in messages: "auto", "aabb", "bvh", "gpu", "cullide", "far",
/// "far-exact-offset", "fcl", "exact"; "occlusion-query", "id-buffer"; "object-pcs", "pairs",
/// "pcs", "contacts", "distance"; "depth16", "depth24", "depth32f". Parse* return nullopt for
/// unknown names.
std::string_view ToString(Method method);
std::string_view ToString(QueryMechanism mechanism);
std::string_view ToString(Output output);
std::string_view ToString(DepthFormat format);
std::optional<Method> ParseMethod(std::string_view name);
std::optional<QueryMechanism> ParseMechanism(std::string_view name);
std::optional<Output> ParseOutput(std::string_view name);
std::optional<DepthFormat> ParseDepthFormat(std::string_view name);

/// The known names, comma-separated ("auto, aabb, bvh, ..."), for help texts and errors.
std::string MethodNames();
std::string MechanismNames();
std::string OutputNames();
std::string DepthFormatNames();

/// True for the methods whose answer never misses a contact (everything but cullide, whose
/// unfattened primitives can be pruned, and fcl, whose triangle test is wrong on hard cases).
bool IsReliable(Method method);

/// True for the methods that cull on the GPU's rasterizer (far, far-exact-offset, cullide).
bool IsGpuMethod(Method method);
/// True for the methods that need a GL context: the raster ones and gpu (compute shaders).
bool NeedsGl(Method method);

/// Checks a request against the limits of far/base/limits.h: resolution in [kMinResolution,
/// kMaxResolution], subobject_size in [1, kMaxSubobjectSize], a distance that is finite and in
/// [0, kMaxDistance], output "distance" only with a distance, method "fcl" only without one,
/// geometry only with output "contacts" or "distance".
/// The pipeline and the protocol's validation both call it. Errors (kInvalidArgument) start
/// with the field: "resolution: 5 is outside [8, 8192]".
Result<void> CheckStepRequest(const StepRequest& request);

}  // namespace far
