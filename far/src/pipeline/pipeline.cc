#include "far/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>

#include "fcl_collider.h"
#include "gl/culling_renderer.h"

#include "far/bounding_offset.h"
#include "far/exact_stage.h"
#include "far/sweep_and_prune.h"
#include "far/thread_pool.h"

namespace far {
namespace {

using internal::AxisView;
using internal::CullingRenderer;
using internal::PieceSet;
using internal::ViewObject;
using Clock = std::chrono::steady_clock;

double MillisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

bool AllFinite(const std::vector<Eigen::Vector3d>& points) {
  return std::all_of(points.begin(), points.end(),
                     [](const Eigen::Vector3d& p) { return p.allFinite(); });
}

// Validates a pose and returns it as an isometry with a normalized rotation.
Result<Eigen::Isometry3d> CheckedPose(const Pose& pose, const std::string& where) {
  if (!pose.translation.allFinite() || !pose.rotation.coeffs().allFinite()) {
    return MakeError(ErrorCode::kInvalidArgument, where + ": pose has a non-finite number");
  }
  const double norm = pose.rotation.norm();
  if (std::abs(norm - 1.0) > 1e-6) {
    return MakeError(
        ErrorCode::kInvalidArgument,
        where + ": rotation is not a unit quaternion (norm " + std::to_string(norm) + ")");
  }
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = pose.rotation.normalized().toRotationMatrix();
  X.translation() = pose.translation;
  return X;
}

// The world AABB of a box given in a frame moved by X.
Eigen::AlignedBox3d TransformBox(const Eigen::Isometry3d& X, const Eigen::AlignedBox3d& box) {
  const Eigen::Vector3d center = X * box.center();
  const Eigen::Vector3d half = X.linear().cwiseAbs() * (0.5 * box.sizes());
  return Eigen::AlignedBox3d(center - half, center + half);
}

std::vector<PieceSet> PieceSetsFor(Method method) {
  switch (method) {
    case Method::kFar:
      return {PieceSet::kUobb};
    case Method::kFarExactOffset:
      return {PieceSet::kEdgeBoxes, PieceSet::kPrisms};
    case Method::kCullide:
      return {PieceSet::kTriangles};
    default:
      return {};
  }
}

bool IsGpuMethod(Method method) {
  return method == Method::kFar || method == Method::kFarExactOffset || method == Method::kCullide;
}

// One object of the scene and what is cached for it.
struct ObjectState {
  uint32_t id = 0;
  uint32_t slot = 0;
  Motion motion = Motion::kStatic;
  Mesh mesh;  // frame M
  Eigen::Isometry3d X_WM = Eigen::Isometry3d::Identity();
  uint64_t geometry_stamp = 0;  // changes whenever p_MV changes
  // Derived from p_MV (recomputed only when the vertices change):
  Eigen::Vector3d anchor_M = Eigen::Vector3d::Zero();  // middle of the mesh: frame A's origin
  double local_extent = 0;                             // bound on |x| of pieces in frame A
  std::vector<Eigen::AlignedBox3d> rect_boxes_M;       // per triangle, its rectangle's AABB
  Eigen::AlignedBox3d rect_box_M;                      // union of rect_boxes_M
  // Derived from p_MV and the pose (recomputed when either changes):
  bool world_dirty = true;
  std::vector<Eigen::Vector3d> p_WV;
  Eigen::AlignedBox3d box_W;  // AABB of the world vertices

  Eigen::Isometry3d X_WA() const { return X_WM * Eigen::Translation3d(anchor_M); }
};

}  // namespace

struct Pipeline::Impl {
  PipelineOptions options;
  std::unique_ptr<GlContext> gl;  // owned context, unless the caller's current one is used
  bool has_gl = false;
  std::string renderer_name = "none";
  ThreadPool pool;
  std::map<uint32_t, ObjectState> objects;  // by id: deterministic order
  std::vector<uint32_t> free_slots;
  uint32_t next_slot = 0;
  uint64_t next_stamp = 1;
  SceneCounters counters;
  SweepAndPrune sap;
  internal::FclCollider fcl;
  // One renderer per raster format; each keeps its own GPU pieces, built from these stamps.
  struct RendererEntry {
    std::unique_ptr<CullingRenderer> renderer;
    std::map<std::pair<uint32_t, int>, uint64_t> built;  // (slot, set) -> geometry stamp
  };
  std::map<std::tuple<int, int, int>, RendererEntry> renderers;

  explicit Impl(const PipelineOptions& o) : options(o), pool(o.num_threads) {}

  // Recomputes what depends on the vertices only.
  void RefreshGeometry(ObjectState& object) {
    object.geometry_stamp = next_stamp++;
    Eigen::AlignedBox3d box_M;
    for (const auto& p : object.mesh.p_MV) box_M.extend(p);
    object.anchor_M = box_M.center();
    double extent = 0;
    for (const auto& p : object.mesh.p_MV)
      extent = std::max(extent, (p - object.anchor_M).cwiseAbs().maxCoeff());
    // A rectangle corner is within one edge length (<= 2 extent) of a vertex.
    object.local_extent = 3.0 * extent;
    object.rect_boxes_M.resize(object.mesh.triangles.size());
    object.rect_box_M.setEmpty();
    for (size_t t = 0; t < object.mesh.triangles.size(); ++t) {
      const auto& tri = object.mesh.triangles[t];
      const Obb rect = TriangleRectangle(object.mesh.p_MV[tri[0]], object.mesh.p_MV[tri[1]],
                                         object.mesh.p_MV[tri[2]]);
      object.rect_boxes_M[t] = ObbAabb(rect);
      object.rect_box_M.extend(object.rect_boxes_M[t]);
    }
    object.world_dirty = true;
  }

  void RefreshWorld(ObjectState& object) {
    if (!object.world_dirty) return;
    object.p_WV.resize(object.mesh.p_MV.size());
    object.box_W.setEmpty();
    for (size_t v = 0; v < object.p_WV.size(); ++v) {
      object.p_WV[v] = object.X_WM * object.mesh.p_MV[v];
      object.box_W.extend(object.p_WV[v]);
    }
    object.world_dirty = false;
    counters.world_updates++;
  }

  Result<RendererEntry*> RendererFor(const StepRequest& request) {
    if (!has_gl)
      return MakeError(ErrorCode::kUnavailable,
                       "method '" + std::string(ToString(request.method)) +
                           "' needs the GPU, and this pipeline has no GL context");
    const RasterFormat raster{request.resolution, request.resolution, request.depth_format};
    auto key = std::make_tuple(raster.width, raster.height, static_cast<int>(raster.depth));
    auto it = renderers.find(key);
    if (it == renderers.end()) {
      auto renderer = CullingRenderer::Create(raster);
      if (!renderer.ok()) return renderer.error();
      it = renderers.emplace(key, RendererEntry{std::move(*renderer), {}}).first;
    }
    return &it->second;
  }

  // Builds the GPU pieces of every object that lacks them or whose vertices changed.
  void EnsurePieces(RendererEntry& entry, std::span<const PieceSet> sets) {
    for (auto& [id, object] : objects) {
      for (PieceSet set : sets) {
        auto key = std::make_pair(object.slot, static_cast<int>(set));
        auto it = entry.built.find(key);
        if (it != entry.built.end() && it->second == object.geometry_stamp) continue;
        std::vector<internal::PieceInstance> pieces;
        pieces.reserve(object.mesh.triangles.size() * internal::InstancesPerTriangle(set));
        for (size_t t = 0; t < object.mesh.triangles.size(); ++t) {
          const auto& tri = object.mesh.triangles[t];
          internal::AppendPieces(set, object.slot, static_cast<uint32_t>(t),
                                 object.mesh.p_MV[tri[0]] - object.anchor_M,
                                 object.mesh.p_MV[tri[1]] - object.anchor_M,
                                 object.mesh.p_MV[tri[2]] - object.anchor_M, &pieces);
        }
        counters.piece_builds++;
        counters.piece_bytes +=
            static_cast<int64_t>(pieces.size() * sizeof(internal::PieceInstance));
        entry.renderer->SetPieces(set, object.slot, std::move(pieces));
        entry.built[key] = object.geometry_stamp;
      }
    }
  }

  // Culls one level (objects, or sub-objects of k triangles) with three axis views, each with
  // projection bounds recomputed from the primitives still alive. `alive` is in/out.
  Result<void> CullLevel(RendererEntry& entry, const StepRequest& request,
                         std::span<const ViewObject> view_objects, int k,
                         std::span<const Eigen::AlignedBox3d> primitive_boxes_W,
                         std::vector<uint8_t>& alive, StepStats& stats, double* radius) {
    const std::vector<PieceSet> sets = PieceSetsFor(request.method);
    const double distance = request.distance.value_or(0.0);
    for (int axis = 0; axis < 3; ++axis) {
      // A primitive can only be kept by another group: stop when one group or none is left.
      std::set<uint32_t> groups;
      Eigen::AlignedBox3d bounds;
      int live = 0;
      for (const ViewObject& object : view_objects) {
        const uint32_t count = k > 0 ? (object.num_triangles + k - 1) / k : 1;
        for (uint32_t j = 0; j < count; ++j) {
          if (!alive[object.first_primitive + j]) continue;
          groups.insert(object.group);
          bounds.extend(primitive_boxes_W[object.first_primitive + j]);
          ++live;
        }
      }
      if (groups.size() < 2) {
        std::fill(alive.begin(), alive.end(), 0);
        return {};
      }
      AxisView view;
      view.axis = axis;
      view.projection = ComputeProjection(bounds, entry.renderer->raster(), distance);
      view.objects = view_objects;
      view.triangles_per_primitive = k;
      view.num_primitives = static_cast<int>(alive.size());
      view.alive = alive;
      view.sets = sets;
      internal::RenderCounters counters;
      auto stays = entry.renderer->RenderView(view, request.mechanism, &counters);
      if (!stays.ok()) return stays.error();
      alive = std::move(*stays);
      stats.primitives_rendered += live;
      stats.draws += counters.draws;
      stats.queries += counters.queries;
      stats.bytes_uploaded += counters.bytes_uploaded;
      *radius = view.projection.radius;
    }
    return {};
  }

  ViewObject MakeViewObject(const ObjectState& object, uint32_t group, uint32_t first_primitive) {
    ViewObject view;
    view.slot = object.slot;
    view.group = group;
    view.first_primitive = first_primitive;
    view.num_triangles = static_cast<uint32_t>(object.mesh.triangles.size());
    view.X_WA = object.X_WA();
    view.local_extent = object.local_extent;
    return view;
  }

  Result<StepResult> Step(const StepRequest& request);
  Result<void> CheckRequest(const StepRequest& request) const;
};

Result<void> Pipeline::Impl::CheckRequest(const StepRequest& request) const {
  if (request.resolution < 8 || request.resolution > 8192) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "resolution: " + std::to_string(request.resolution) + " is outside [8, 8192]");
  }
  if (request.subobject_size < 1 || request.subobject_size > 1 << 20) {
    return MakeError(
        ErrorCode::kInvalidArgument,
        "subobject_size: " + std::to_string(request.subobject_size) + " is outside [1, 2^20]");
  }
  if (request.distance && (!std::isfinite(*request.distance) || *request.distance < 0)) {
    return MakeError(ErrorCode::kInvalidArgument, "distance: " + std::to_string(*request.distance) +
                                                      " is not a finite number >= 0");
  }
  if (request.output == Output::kDistancePairs && !request.distance) {
    return MakeError(ErrorCode::kInvalidArgument, "output: 'distance' needs a distance D");
  }
  if (request.method == Method::kFcl && request.distance) {
    return MakeError(
        ErrorCode::kInvalidArgument,
        "method: 'fcl' answers contacts only; distance queries need far, aabb or exact");
  }
  return {};
}

Result<StepResult> Pipeline::Impl::Step(const StepRequest& request) {
  if (auto ok = CheckRequest(request); !ok.ok()) return ok.error();
  const auto step_start = Clock::now();
  StepResult result;
  StepStats& stats = result.stats;
  auto stage_start = Clock::now();
  auto end_stage = [&](const char* name) {
    stats.stages.push_back({name, MillisecondsSince(stage_start)});
    stage_start = Clock::now();
  };
  auto finish = [&]() -> Result<StepResult> {
    stats.total_ms = MillisecondsSince(step_start);
    return std::move(result);
  };
  const double distance = request.distance.value_or(0.0);
  const bool want_exact =
      request.output == Output::kContacts || request.output == Output::kDistancePairs;

  // Update: world-frame vertices of objects that moved or deformed.
  for (auto& [id, object] : objects) RefreshWorld(object);
  end_stage("update");

  // Views of all objects, in id order (index i of `all` is group i).
  std::vector<const ObjectState*> all;
  std::vector<WorldObjectView> world;
  for (const auto& [id, object] : objects) {
    all.push_back(&object);
    world.push_back({id, object.p_WV, object.mesh.triangles});
  }

  // The reference and FCL answer at once, without culling stages.
  if (request.method == Method::kExact || request.method == Method::kFcl) {
    ExactResult exact;
    std::optional<size_t> broadphase_pairs;  // FCL's candidate object pairs
    if (request.method == Method::kExact) {
      exact = BruteForceReference(world, request.distance, pool);
    } else {
      std::vector<internal::FclCollider::Object> fcl_objects;
      for (const ObjectState* object : all) {
        fcl_objects.push_back({object->id, object->geometry_stamp, &object->mesh, object->X_WM});
      }
      internal::FclCollider::CollideStats fcl_stats;
      exact.contacts = fcl.Collide(fcl_objects, &fcl_stats);
      exact.pairs_considered = fcl_stats.triangle_pairs_considered;
      exact.pairs_tested = fcl_stats.triangle_tests;
      broadphase_pairs = fcl_stats.object_pairs;
    }
    end_stage("exact");
    std::set<uint32_t> pcs;
    std::set<ObjectPair> pairs;
    auto note = [&](const ContactPair& c) {
      pcs.insert(c.object_a);
      pcs.insert(c.object_b);
      pairs.insert({c.object_a, c.object_b});
      result.pcs_primitives[c.object_a].push_back(c.triangle_a);
      result.pcs_primitives[c.object_b].push_back(c.triangle_b);
    };
    for (const auto& c : exact.contacts) note(c);
    for (const auto& d : exact.distance_pairs) note(d.pair);
    for (auto& [id, tris] : result.pcs_primitives) {
      std::sort(tris.begin(), tris.end());
      tris.erase(std::unique(tris.begin(), tris.end()), tris.end());
    }
    result.pcs_objects.assign(pcs.begin(), pcs.end());
    result.object_pairs.assign(pairs.begin(), pairs.end());
    result.contacts = std::move(exact.contacts);
    result.distance_pairs = std::move(exact.distance_pairs);
    stats.object_pairs = static_cast<int64_t>(broadphase_pairs.value_or(pairs.size()));
    stats.pairs_tested = static_cast<int64_t>(exact.pairs_tested);
    stats.pairs_considered = static_cast<int64_t>(exact.pairs_considered);
    return finish();
  }

  // Object-level culling -> object PCS (AABB: every object goes to sweep-and-prune).
  RendererEntry* entry = nullptr;
  std::vector<uint8_t> object_alive(all.size(), 1);
  if (IsGpuMethod(request.method)) {
    auto renderer = RendererFor(request);
    if (!renderer.ok()) return renderer.error();
    entry = *renderer;
    const std::vector<PieceSet> sets = PieceSetsFor(request.method);
    EnsurePieces(*entry, sets);
    std::vector<ViewObject> view_objects;
    std::vector<Eigen::AlignedBox3d> boxes;
    for (size_t i = 0; i < all.size(); ++i) {
      view_objects.push_back(
          MakeViewObject(*all[i], static_cast<uint32_t>(i), static_cast<uint32_t>(i)));
      boxes.push_back(TransformBox(all[i]->X_WM, all[i]->rect_box_M));
    }
    if (auto ok = CullLevel(*entry, request, view_objects, 0, boxes, object_alive, stats,
                            &stats.object_radius);
        !ok.ok()) {
      return ok.error();
    }
    for (size_t i = 0; i < all.size(); ++i) {
      if (object_alive[i]) result.pcs_objects.push_back(all[i]->id);
    }
  } else {
    for (const ObjectState* object : all) result.pcs_objects.push_back(object->id);
  }
  end_stage("object_cull");
  if (request.output == Output::kObjectPcs && request.method != Method::kAabb) return finish();

  // Sweep-and-prune on the PCS objects' AABBs (margin D for distance queries).
  std::vector<IdBox> id_boxes;
  for (size_t i = 0; i < all.size(); ++i) {
    if (object_alive[i]) id_boxes.push_back({all[i]->id, all[i]->box_W});
  }
  result.object_pairs = sap.Update(id_boxes, distance);
  stats.object_pairs = static_cast<int64_t>(result.object_pairs.size());
  if (request.method == Method::kAabb) {
    // I-COLLIDE: the PCS is the set of objects in some overlapping pair.
    std::set<uint32_t> paired;
    for (const auto& pair : result.object_pairs) paired.insert({pair.object_a, pair.object_b});
    result.pcs_objects.assign(paired.begin(), paired.end());
  }
  end_stage("sweep_and_prune");
  if (request.output == Output::kObjectPcs || request.output == Output::kObjectPairs)
    return finish();

  // Sub-object culling of the objects in candidate pairs -> primitive PCS.
  std::map<uint32_t, size_t> index_of;
  for (size_t i = 0; i < all.size(); ++i) index_of[all[i]->id] = i;
  std::set<size_t> paired;
  for (const auto& pair : result.object_pairs) {
    paired.insert(index_of[pair.object_a]);
    paired.insert(index_of[pair.object_b]);
  }
  std::vector<std::vector<uint32_t>> subsets(all.size());
  const int k = request.subobject_size;
  if (IsGpuMethod(request.method)) {
    std::vector<ViewObject> view_objects;
    std::vector<Eigen::AlignedBox3d> boxes;
    for (size_t i : paired) {
      const ObjectState& object = *all[i];
      view_objects.push_back(
          MakeViewObject(object, static_cast<uint32_t>(i), static_cast<uint32_t>(boxes.size())));
      const size_t n = object.mesh.triangles.size();
      for (size_t first = 0; first < n; first += static_cast<size_t>(k)) {
        Eigen::AlignedBox3d box_M;
        for (size_t t = first; t < std::min(n, first + static_cast<size_t>(k)); ++t)
          box_M.extend(object.rect_boxes_M[t]);
        boxes.push_back(TransformBox(object.X_WM, box_M));
      }
    }
    std::vector<uint8_t> alive(boxes.size(), 1);
    if (auto ok = CullLevel(*entry, request, view_objects, k, boxes, alive, stats,
                            &stats.primitive_radius);
        !ok.ok()) {
      return ok.error();
    }
    for (const ViewObject& view : view_objects) {
      const uint32_t count = (view.num_triangles + k - 1) / k;
      for (uint32_t j = 0; j < count; ++j) {
        if (!alive[view.first_primitive + j]) continue;
        for (uint32_t t = j * k; t < std::min(view.num_triangles, (j + 1) * k); ++t)
          subsets[view.group].push_back(t);
      }
    }
  } else {
    // AABB baseline: triangles whose box overlaps a partner object's box (grown by D).
    for (const auto& pair : result.object_pairs) {
      const size_t a = index_of[pair.object_a], b = index_of[pair.object_b];
      for (auto [self, other] : {std::make_pair(a, b), std::make_pair(b, a)}) {
        Eigen::AlignedBox3d partner = all[other]->box_W;
        partner.min().array() -= distance;
        partner.max().array() += distance;
        const ObjectState& object = *all[self];
        for (size_t t = 0; t < object.mesh.triangles.size(); ++t) {
          Eigen::AlignedBox3d tri_box;
          for (uint32_t v : object.mesh.triangles[t]) tri_box.extend(object.p_WV[v]);
          if (tri_box.intersects(partner)) subsets[self].push_back(static_cast<uint32_t>(t));
        }
      }
    }
    for (auto& subset : subsets) {
      std::sort(subset.begin(), subset.end());
      subset.erase(std::unique(subset.begin(), subset.end()), subset.end());
    }
  }
  for (size_t i : paired) {
    if (!subsets[i].empty()) result.pcs_primitives[all[i]->id] = subsets[i];
  }
  end_stage("primitive_cull");
  if (!want_exact) return finish();

  // Exact tests on the CPU pool: PCS triangles of candidate object pairs.
  ExactQuery query;
  query.objects = world;
  query.object_pairs = result.object_pairs;
  query.triangle_subsets = subsets;
  query.want_contacts = true;
  query.max_distance = request.output == Output::kDistancePairs ? request.distance : std::nullopt;
  ExactResult exact = RunExactTests(query, pool);
  result.contacts = std::move(exact.contacts);
  result.distance_pairs = std::move(exact.distance_pairs);
  stats.pairs_considered = static_cast<int64_t>(exact.pairs_considered);
  stats.pairs_tested = static_cast<int64_t>(exact.pairs_tested);
  end_stage("exact");
  return finish();
}

Pipeline::Pipeline(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Pipeline::~Pipeline() = default;

Result<std::unique_ptr<Pipeline>> Pipeline::Create(const PipelineOptions& options) {
  auto impl = std::make_unique<Impl>(options);
  if (options.use_gl && !options.use_current_context) {
    auto gl = GlContext::Create(options.platform);
    if (!gl.ok()) return gl.error();
    impl->gl = std::move(*gl);
    impl->renderer_name = impl->gl->renderer();
  } else if (options.use_gl) {
    impl->renderer_name = internal::CurrentGlRenderer();
    if (impl->renderer_name.empty()) {
      return MakeError(ErrorCode::kUnavailable,
                       "use_current_context: no GL context is current on this thread");
    }
  }
  impl->has_gl = options.use_gl;
  return std::unique_ptr<Pipeline>(new Pipeline(std::move(impl)));
}

Result<void> Pipeline::AddObject(uint32_t id, Mesh mesh, Motion motion, const Pose& X_WO) {
  const std::string where = "object " + std::to_string(id);
  if (impl_->objects.count(id))
    return MakeError(ErrorCode::kInvalidArgument, where + ": id is already in use");
  if (mesh.triangles.empty())
    return MakeError(ErrorCode::kInvalidArgument, where + ": mesh has no triangles");
  if (!AllFinite(mesh.p_MV))
    return MakeError(ErrorCode::kInvalidArgument, where + ": a vertex is not finite");
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (uint32_t v : mesh.triangles[t]) {
      if (v >= mesh.p_MV.size()) {
        return MakeError(ErrorCode::kInvalidArgument, where + ": triangle " + std::to_string(t) +
                                                          " has vertex index " + std::to_string(v) +
                                                          " >= vertex count " +
                                                          std::to_string(mesh.p_MV.size()));
      }
    }
  }
  auto X = CheckedPose(X_WO, where);
  if (!X.ok()) return X.error();
  ObjectState object;
  object.id = id;
  object.motion = motion;
  object.mesh = std::move(mesh);
  object.X_WM = *X;
  if (!impl_->free_slots.empty()) {
    object.slot = impl_->free_slots.back();
    impl_->free_slots.pop_back();
  } else {
    object.slot = impl_->next_slot++;
  }
  impl_->RefreshGeometry(object);
  impl_->objects.emplace(id, std::move(object));
  return {};
}

Result<void> Pipeline::RemoveObject(uint32_t id) {
  auto it = impl_->objects.find(id);
  if (it == impl_->objects.end())
    return MakeError(ErrorCode::kNotFound, "object " + std::to_string(id) + ": no such object");
  const uint32_t slot = it->second.slot;
  for (auto& [key, entry] : impl_->renderers) {
    entry.renderer->RemoveSlot(slot);
    for (int set = 0; set < internal::kNumPieceSets; ++set) entry.built.erase({slot, set});
  }
  impl_->fcl.Remove(id);
  impl_->free_slots.push_back(slot);
  impl_->objects.erase(it);
  return {};
}

Result<void> Pipeline::SetPose(uint32_t id, const Pose& X_WO) {
  const std::string where = "object " + std::to_string(id);
  auto it = impl_->objects.find(id);
  if (it == impl_->objects.end())
    return MakeError(ErrorCode::kNotFound, where + ": no such object");
  if (it->second.motion == Motion::kStatic) {
    return MakeError(ErrorCode::kInvalidArgument, where + ": static objects cannot move");
  }
  auto X = CheckedPose(X_WO, where);
  if (!X.ok()) return X.error();
  if (!X->isApprox(it->second.X_WM, 0.0)) {
    it->second.X_WM = *X;
    it->second.world_dirty = true;
  }
  return {};
}

Result<void> Pipeline::SetVertices(uint32_t id, std::vector<Eigen::Vector3d> p_MV) {
  const std::string where = "object " + std::to_string(id);
  auto it = impl_->objects.find(id);
  if (it == impl_->objects.end())
    return MakeError(ErrorCode::kNotFound, where + ": no such object");
  ObjectState& object = it->second;
  if (object.motion != Motion::kDeformable) {
    return MakeError(ErrorCode::kInvalidArgument,
                     where + ": only deformable objects take new vertices");
  }
  if (p_MV.size() != object.mesh.p_MV.size()) {
    return MakeError(ErrorCode::kInvalidArgument, where + ": " + std::to_string(p_MV.size()) +
                                                      " vertices given, the mesh has " +
                                                      std::to_string(object.mesh.p_MV.size()));
  }
  if (!AllFinite(p_MV))
    return MakeError(ErrorCode::kInvalidArgument, where + ": a vertex is not finite");
  object.mesh.p_MV = std::move(p_MV);
  impl_->RefreshGeometry(object);
  return {};
}

Result<void> Pipeline::LoadScene(const Scene& scene) {
  for (const SceneObject& object : scene.objects) {
    if (auto ok = AddObject(object.id, object.mesh, object.motion, object.X_WO); !ok.ok())
      return ok;
  }
  return {};
}

Result<StepResult> Pipeline::Step(const StepRequest& request) { return impl_->Step(request); }
int Pipeline::num_objects() const { return static_cast<int>(impl_->objects.size()); }
const SceneCounters& Pipeline::counters() const { return impl_->counters; }
std::string Pipeline::gl_renderer() const { return impl_->renderer_name; }

}  // namespace far
