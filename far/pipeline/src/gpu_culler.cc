#include "gpu_culler.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>

#include "stop_error.h"

#include "far/gpu/gl_lock.h"
#include "far/offsets/bounding_offset.h"

namespace far::internal {
namespace {

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

// What the object level draws: for the FAR methods a few boxes per object (a cut of its
// hierarchy), which cost far less than every triangle's offset and only ever prune less; for
// CULLIDE the triangles themselves.
std::vector<PieceSet> ObjectLevelSetsFor(Method method) {
  if (method == Method::kCullide) return {PieceSet::kTriangles};
  return {PieceSet::kProxyBoxes};
}

// Up to `max_boxes` nodes of `bvh` that together hold every triangle: the biggest node is
// split until there are enough or only leaves are left.
std::vector<const TriangleBvh::Node*> HierarchyCut(const TriangleBvh& bvh, size_t max_boxes) {
  const auto& nodes = bvh.nodes();
  auto smaller = [](const TriangleBvh::Node* x, const TriangleBvh::Node* y) {
    return x->half_extent.sum() < y->half_extent.sum();
  };
  std::vector<const TriangleBvh::Node*> cut = {&nodes[0]}, leaves;
  while (!cut.empty() && cut.size() + leaves.size() < max_boxes) {
    std::pop_heap(cut.begin(), cut.end(), smaller);
    const TriangleBvh::Node* biggest = cut.back();
    cut.pop_back();
    if (biggest->leaf()) {
      leaves.push_back(biggest);
      continue;
    }
    for (uint32_t child : {biggest->first, biggest->first + 1}) {
      cut.push_back(&nodes[child]);
      std::push_heap(cut.begin(), cut.end(), smaller);
    }
  }
  cut.insert(cut.end(), leaves.begin(), leaves.end());
  return cut;
}

// Boxes per object at the object level: more for big objects (an occluder as coarse as one box
// would keep everything around it), about one per 64 triangles, at most 256.
size_t ProxyBoxesFor(const CachedObject& object) {
  return std::clamp<size_t>(object.mesh.triangles.size() / 64, 1, 256);
}

// The world AABB of a box given in a frame moved by X.
Eigen::AlignedBox3d TransformBox(const Eigen::Isometry3d& X, const Eigen::AlignedBox3d& box) {
  const Eigen::Vector3d center = X * box.center();
  const Eigen::Vector3d half = X.linear().cwiseAbs() * (0.5 * box.sizes());
  return Eigen::AlignedBox3d(center - half, center + half);
}

// An object drawn in a view: its slot is its group (each object its own).
ViewObject MakeViewObject(const CachedObject& object, uint32_t first_primitive) {
  ViewObject view;
  view.slot = static_cast<uint32_t>(Index(object.slot));
  view.group = view.slot;
  view.first_primitive = first_primitive;
  view.num_triangles = static_cast<uint32_t>(object.mesh.triangles.size());
  view.X_WA = object.X_WA();
  view.local_extent = object.local_extent;
  return view;
}

// Primitives of a view object: sub-objects of k triangles, or the whole object when k = 0.
uint32_t PrimitivesOf(const ViewObject& object, int k) {
  return k > 0 ? (object.num_triangles + static_cast<uint32_t>(k) - 1) / static_cast<uint32_t>(k)
               : 1;
}

// Folds one view's projection into its level's certificate: the largest of each number over
// the level's views, the union of the bounds of the primitives they drew. Unfattened
// primitives (CULLIDE) are drawn with no offset: radius 0, which is why CULLIDE can miss.
void AddView(const Projection& projection, const Eigen::AlignedBox3d& primitive_bounds_W,
             int resolution, bool fattened, LevelCertificate& level) {
  level.views++;
  level.resolution = resolution;
  level.offset_radius = std::max(level.offset_radius, fattened ? projection.radius : 0.0);
  level.pixel_size = std::max(level.pixel_size, projection.pixel_size);
  level.depth_step = std::max(level.depth_step, projection.depth_step);
  level.rounding = std::max(level.rounding, projection.rounding);
  for (int i = 0; i < 3; ++i) {
    const bool first = level.views == 1;
    level.world_min[i] = first ? primitive_bounds_W.min()[i]
                               : std::min(level.world_min[i], primitive_bounds_W.min()[i]);
    level.world_max[i] = first ? primitive_bounds_W.max()[i]
                               : std::max(level.world_max[i], primitive_bounds_W.max()[i]);
  }
}

// The projection for primitives within `bounds` whose views also hold every drawn piece as
// the GPU grows it: by radius_scale (r + its object's FloatRoundingBound), reaching up to
// sqrt(3) times that along a world axis when tilted. That float margin follows the object's
// extent and distance from the view, not the view: around a tiny live region of a big object
// it can be a billion views wide, and llvmpipe's clipper, interpolating such a primitive in
// float, put it off the viewport (a contact of two 1e-12 triangles on an object 1e3 across
// was lost). Growing the view by the margin keeps every piece within a few view sizes. The
// margin changes by 16 ulps of the growth, so doubling it settles in one more round.
Projection ProjectionHoldingMargins(const Eigen::AlignedBox3d& bounds, const RasterFormat& raster,
                                    double distance, std::span<const ViewObject> drawn,
                                    double radius_scale) {
  Projection projection = ComputeProjection(bounds, raster, distance);
  double grown = 0;
  for (int round = 0; round < 8; ++round) {
    double margin = 0;
    for (const ViewObject& object : drawn)
      margin = std::max(margin, FloatRoundingBound(object, projection));
    const double reach = std::sqrt(3.0) * radius_scale * margin;
    if (reach <= grown) break;
    grown = 2 * reach;
    projection = ComputeProjection(
        Eigen::AlignedBox3d(bounds.min().array() - grown, bounds.max().array() + grown), raster,
        distance);
  }
  return projection;
}

// The level's certificate goes with the step's stats when a view was rendered (with fewer than
// two groups left nothing needs drawing: nothing can touch).
void RecordLevel(const LevelCertificate& level, StepStats& stats, double& radius) {
  radius = level.offset_radius;
  if (level.views > 0) stats.certificate.levels.push_back(level);
}

}  // namespace

GpuCuller::RendererKeyType GpuCuller::RendererKey(const StepRequest& request) {
  return {request.resolution, request.resolution, static_cast<int>(request.depth_format)};
}

Result<GpuCuller::RendererEntry*> GpuCuller::RendererFor(const StepRequest& request) {
  const RasterFormat raster{request.resolution, request.resolution, request.depth_format};
  const RendererKeyType key = RendererKey(request);
  auto it = renderers_.find(key);
  if (it == renderers_.end()) {
    const auto gl = LockGl();  // compiles shaders, makes framebuffers
    auto renderer = CullingRenderer::Create(raster);
    if (!renderer.ok()) return renderer.error();
    (*renderer)->set_batch_ms(batch_ms_);
    it = renderers_.emplace(key, RendererEntry{std::move(*renderer), {}}).first;
  }
  return &it->second;
}

namespace {

// The renderers' name of an object's slot.
uint32_t Slot(const CachedObject& object) { return static_cast<uint32_t>(Index(object.slot)); }

// Triangles between two polls of the step's stopper while pieces are built.
constexpr size_t kPiecesPerPoll = 1 << 15;

// The GPU pieces of one object in one set, in the object's anchored frame; nullopt when the
// stopper stopped it.
std::optional<std::vector<PieceInstance>> BuildPieces(const CachedObject& object, PieceSet set,
                                                      StepStopper& stopper) {
  std::vector<PieceInstance> pieces;
  if (set == PieceSet::kProxyBoxes) {
    // @pre the hierarchy is up to date (SceneCache::RefreshHierarchies).
    for (const TriangleBvh::Node* node : HierarchyCut(object.bvh, ProxyBoxesFor(object)))
      pieces.push_back(
          ProxyBoxPiece(Slot(object), node->center - object.anchor_M, node->half_extent));
    return pieces;
  }
  pieces.reserve(object.mesh.triangles.size() * InstancesPerTriangle(set));
  for (size_t t = 0; t < object.mesh.triangles.size(); ++t) {
    if (t % kPiecesPerPoll == kPiecesPerPoll - 1 && stopper.Poll()) return std::nullopt;
    const auto& tri = object.mesh.triangles[t];
    AppendPieces(set, Slot(object), static_cast<uint32_t>(t),
                 object.mesh.p_MV[tri[0]] - object.anchor_M,
                 object.mesh.p_MV[tri[1]] - object.anchor_M,
                 object.mesh.p_MV[tri[2]] - object.anchor_M, &pieces);
  }
  return pieces;
}

}  // namespace

// Builds the GPU pieces of every object that lacks them or whose vertices changed: on the pool
// (deformable objects change every step: 150 leaves rebuild 19K triangles' pieces), then
// handed to the renderer on this thread, the GL thread. Stopped, it hands over those it
// finished (a later step builds the others) and says why.
StopReason GpuCuller::EnsurePieces(RendererEntry& entry,
                                   std::span<const CachedObject* const> objects,
                                   std::span<const PieceSet> sets, const StepControl& control) {
  // The pieces an object never had here first (one-off: setup), then those whose vertices
  // changed (deformable objects, every step).
  std::vector<std::pair<const CachedObject*, PieceSet>> stale, changed;
  for (const CachedObject* object : objects) {
    if (object == nullptr) continue;
    for (PieceSet set : sets) {
      auto it = entry.built.find({Slot(*object), static_cast<int>(set)});
      if (it == entry.built.end()) {
        stale.emplace_back(object, set);
      } else if (it->second != object->geometry_stamp) {
        changed.emplace_back(object, set);
      }
    }
  }
  const size_t first_builds = stale.size();
  stale.insert(stale.end(), changed.begin(), changed.end());
  std::vector<std::optional<std::vector<PieceInstance>>> built(stale.size());
  StepStopper stopper(&control);
  const auto build = [&](size_t from, size_t to) {
    pool_.ParallelFor(to - from, 1, [&](size_t begin, size_t end) {
      for (size_t i = from + begin; i < from + end && !stopper.Poll(); ++i)
        built[i] = BuildPieces(*stale[i].first, stale[i].second, stopper);
    });
  };
  if (first_builds > 0) {
    const SetupScope setup(&control);
    build(0, first_builds);
  }
  build(first_builds, stale.size());
  for (size_t i = 0; i < stale.size(); ++i) {
    if (!built[i]) continue;
    const auto [object, set] = stale[i];
    counters_.piece_builds++;
    counters_.piece_bytes += static_cast<int64_t>(built[i]->size() * sizeof(PieceInstance));
    entry.renderer->SetPieces(set, Slot(*object), std::move(*built[i]));
    entry.built[{Slot(*object), static_cast<int>(set)}] = object->geometry_stamp;
  }
  return stopper.reason();
}

// Culls one level (objects, or sub-objects of k triangles) with three axis views, each with
// projection bounds recomputed from the primitives still alive. `alive` is in/out.
Result<void> GpuCuller::CullLevel(RendererEntry& entry, const StepRequest& request,
                                  std::span<const PieceSet> sets,
                                  std::span<const ViewObject> view_objects, int k,
                                  std::span<const Eigen::AlignedBox3d> primitive_boxes_W,
                                  std::vector<uint8_t>& alive, StepStats& stats,
                                  LevelCertificate& level, const StepControl& control) {
  const Stage stage = k == 0 ? Stage::kObjectCull : Stage::kPrimitiveCull;
  const bool proxies = !sets.empty() && sets[0] == PieceSet::kProxyBoxes;
  const bool fattened = sets.empty() || sets[0] != PieceSet::kTriangles;
  for (int axis = 0; axis < 3; ++axis) {
    // A primitive can only be kept by another group: stop when one group or none is left
    // (each view object is its own group).
    Eigen::AlignedBox3d bounds;
    int live = 0;
    std::vector<ViewObject> drawn;  // the objects with a live primitive (each its own group)
    for (const ViewObject& object : view_objects) {
      const int live_before = live;
      for (uint32_t j = 0; j < PrimitivesOf(object, k); ++j) {
        if (!alive[object.first_primitive + j]) continue;
        bounds.extend(primitive_boxes_W[object.first_primitive + j]);
        ++live;
      }
      if (live > live_before) drawn.push_back(object);
    }
    if (drawn.size() < 2) {
      std::fill(alive.begin(), alive.end(), 0);
      return {};
    }
    AxisView view;
    view.axis = axis;
    view.radius_scale = proxies ? std::sqrt(3.0) : 1.0;
    view.projection = ProjectionHoldingMargins(
        bounds, entry.renderer->raster(), request.distance.value_or(0.0), drawn, view.radius_scale);
    view.objects = view_objects;
    view.triangles_per_primitive = k;
    view.num_primitives = static_cast<int>(alive.size());
    view.alive = alive;
    view.sets = sets;
    if (const StopReason stop = control.Check(); stop != StopReason::kNone)
      return StopError(stop, stage, control);
    RenderCounters counters;
    // The GL lock is held for one view (uploads, passes, read-back), not for the whole stage,
    // and a long view hands it to the threads that wait for it between its batches of draws:
    // other sessions' views take turns with this one's.
    auto stays = [&] {
      auto gl = LockGl();
      const BetweenBatches between = [&] {
        if (gl.contended()) gl.Yield();
        return control.Check();
      };
      // In process with no deadline and no other thread's GL work, nothing needs a pause.
      const bool can_stop = control.cancel != nullptr ||
                            control.deadline != StepControl::Clock::time_point::max() ||
                            control.slow_after != StepControl::Clock::time_point::max();
      const PauseWanted wanted = [&] { return can_stop || gl.contended(); };
      return entry.renderer->RenderView(view, request.mechanism, &counters, between, wanted);
    }();
    if (!stays.ok()) return stays.error();
    if (stays->stopped != StopReason::kNone) return StopError(stays->stopped, stage, control);
    alive = std::move(stays->stays);
    stats.primitives_rendered += live;
    stats.draws += counters.draws;
    stats.queries += counters.queries;
    stats.gl_pauses += counters.pauses;
    stats.bytes_uploaded += counters.bytes_uploaded;
    stats.gl_prepare_ms += counters.prepare_ms;
    stats.gl_passes_ms += counters.passes_ms;
    stats.gl_gpu_ms += counters.gpu_ms;
    AddView(view.projection, bounds, request.resolution, fattened, level);
  }
  return {};
}

GpuCuller::~GpuCuller() {
  const auto gl = LockGl();  // the renderers free their GL objects
  renderers_.clear();
}

Result<std::vector<uint8_t>> GpuCuller::CullObjects(const StepRequest& request,
                                                    std::span<const CachedObject* const> objects,
                                                    StepStats& stats, const StepControl& control) {
  // A renderer's first step (its shaders compiled on first use) is setup. The object stage
  // comes first in every GPU step: it tells the primitive stage which step this is.
  const bool first_step = !renderers_.contains(RendererKey(request));
  std::optional<SetupScope> setup;
  if (first_step) setup.emplace(&control);
  auto entry = RendererFor(request);
  if (!entry.ok()) return entry.error();
  (*entry)->first_step = first_step;
  const std::vector<PieceSet> sets = ObjectLevelSetsFor(request.method);
  if (const StopReason stop = EnsurePieces(**entry, objects, sets, control);
      stop != StopReason::kNone) {
    return StopError(stop, Stage::kObjectCull, control);
  }
  // One primitive per slot (a free slot's is never alive); each object is its own group.
  std::vector<ViewObject> view_objects;
  std::vector<Eigen::AlignedBox3d> boxes(objects.size());
  std::vector<uint8_t> alive(objects.size(), 0);
  for (size_t s = 0; s < objects.size(); ++s) {
    if (objects[s] == nullptr) continue;
    view_objects.push_back(MakeViewObject(*objects[s], static_cast<uint32_t>(s)));
    boxes[s] = TransformBox(objects[s]->X_WM, objects[s]->rect_box_M);
    alive[s] = 1;
  }
  LevelCertificate level{.level = "object"};
  if (auto ok =
          CullLevel(**entry, request, sets, view_objects, 0, boxes, alive, stats, level, control);
      !ok.ok()) {
    return ok.error();
  }
  RecordLevel(level, stats, stats.object_radius);
  return alive;
}

Result<std::vector<std::vector<uint32_t>>> GpuCuller::CullPrimitives(
    const StepRequest& request, std::span<const CachedObject* const> objects,
    std::span<const ObjectSlot> paired, std::span<const std::vector<uint32_t>> candidates,
    StepStats& stats, const StepControl& control) {
  auto entry = RendererFor(request);
  if (!entry.ok()) return entry.error();
  std::optional<SetupScope> setup;  // as in CullObjects
  if (std::exchange((*entry)->first_step, false)) setup.emplace(&control);
  const std::vector<PieceSet> sets = PieceSetsFor(request.method);
  if (const StopReason stop = EnsurePieces(**entry, objects, sets, control);
      stop != StopReason::kNone) {
    return StopError(stop, Stage::kPrimitiveCull, control);
  }
  // Sub-objects of k triangles of the paired objects, each object its own group.
  const int k = request.subobject_size;
  std::vector<ViewObject> view_objects;
  uint32_t num_primitives = 0;
  for (ObjectSlot slot : paired) {
    view_objects.push_back(MakeViewObject(*objects[Index(slot)], num_primitives));
    num_primitives += PrimitivesOf(view_objects.back(), k);
  }
  // Only the sub-objects holding a candidate triangle take part: the others are not drawn.
  std::vector<uint8_t> alive(num_primitives, candidates.empty() ? 1 : 0);
  if (!candidates.empty()) {
    for (const ViewObject& view : view_objects) {
      for (uint32_t t : candidates[view.group]) alive[view.first_primitive + t / k] = 1;
    }
  }
  // World boxes of those only (CullLevel reads no other): a paper-scale bunny has 92K
  // sub-objects, of which the hierarchy leaves a few thousand near the other bunny.
  std::vector<Eigen::AlignedBox3d> boxes(num_primitives);
  for (const ViewObject& view : view_objects) {
    const CachedObject& object = *objects[view.group];
    for (uint32_t j = 0; j < PrimitivesOf(view, k); ++j) {
      if (!alive[view.first_primitive + j]) continue;
      Eigen::AlignedBox3d box_M;
      for (uint32_t t = j * k; t < std::min(view.num_triangles, (j + 1) * k); ++t)
        box_M.extend(object.rect_boxes_M[t]);
      boxes[view.first_primitive + j] = TransformBox(object.X_WM, box_M);
    }
  }
  LevelCertificate level{.level = "sub-object"};
  if (auto ok =
          CullLevel(**entry, request, sets, view_objects, k, boxes, alive, stats, level, control);
      !ok.ok()) {
    return ok.error();
  }
  RecordLevel(level, stats, stats.primitive_radius);
  // Surviving sub-objects back to triangle indices (the candidate ones), per object.
  std::vector<std::vector<uint32_t>> subsets(objects.size());
  for (const ViewObject& view : view_objects) {
    if (candidates.empty()) {
      for (uint32_t j = 0; j < PrimitivesOf(view, k); ++j) {
        if (!alive[view.first_primitive + j]) continue;
        for (uint32_t t = j * k; t < std::min(view.num_triangles, (j + 1) * k); ++t)
          subsets[view.group].push_back(t);
      }
    } else {
      for (uint32_t t : candidates[view.group]) {
        if (alive[view.first_primitive + t / k]) subsets[view.group].push_back(t);
      }
    }
  }
  return subsets;
}

void GpuCuller::RemoveSlot(ObjectSlot slot) {
  // No GL here: the renderers drop the slot's pieces on the CPU and upload at their next view.
  const auto s = static_cast<uint32_t>(Index(slot));
  for (auto& [key, entry] : renderers_) {
    entry.renderer->RemoveSlot(s);
    for (int set = 0; set < kNumPieceSets; ++set) entry.built.erase({s, set});
  }
}

}  // namespace far::internal
