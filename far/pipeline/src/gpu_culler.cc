#include "gpu_culler.h"

#include <algorithm>
#include <set>
#include <string>

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

// The world AABB of a box given in a frame moved by X.
Eigen::AlignedBox3d TransformBox(const Eigen::Isometry3d& X, const Eigen::AlignedBox3d& box) {
  const Eigen::Vector3d center = X * box.center();
  const Eigen::Vector3d half = X.linear().cwiseAbs() * (0.5 * box.sizes());
  return Eigen::AlignedBox3d(center - half, center + half);
}

ViewObject MakeViewObject(const CachedObject& object, uint32_t group, uint32_t first_primitive) {
  ViewObject view;
  view.slot = object.slot;
  view.group = group;
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

}  // namespace

Result<GpuCuller::RendererEntry*> GpuCuller::RendererFor(const StepRequest& request) {
  const RasterFormat raster{request.resolution, request.resolution, request.depth_format};
  auto key = std::make_tuple(raster.width, raster.height, static_cast<int>(raster.depth));
  auto it = renderers_.find(key);
  if (it == renderers_.end()) {
    auto renderer = CullingRenderer::Create(raster);
    if (!renderer.ok()) return renderer.error();
    it = renderers_.emplace(key, RendererEntry{std::move(*renderer), {}}).first;
  }
  return &it->second;
}

// Builds the GPU pieces of every object that lacks them or whose vertices changed.
void GpuCuller::EnsurePieces(RendererEntry& entry, std::span<const CachedObject* const> objects,
                             std::span<const PieceSet> sets) {
  for (const CachedObject* object : objects) {
    for (PieceSet set : sets) {
      auto key = std::make_pair(object->slot, static_cast<int>(set));
      auto it = entry.built.find(key);
      if (it != entry.built.end() && it->second == object->geometry_stamp) continue;
      std::vector<PieceInstance> pieces;
      pieces.reserve(object->mesh.triangles.size() * InstancesPerTriangle(set));
      for (size_t t = 0; t < object->mesh.triangles.size(); ++t) {
        const auto& tri = object->mesh.triangles[t];
        AppendPieces(set, object->slot, static_cast<uint32_t>(t),
                     object->mesh.p_MV[tri[0]] - object->anchor_M,
                     object->mesh.p_MV[tri[1]] - object->anchor_M,
                     object->mesh.p_MV[tri[2]] - object->anchor_M, &pieces);
      }
      counters_.piece_builds++;
      counters_.piece_bytes += static_cast<int64_t>(pieces.size() * sizeof(PieceInstance));
      entry.renderer->SetPieces(set, object->slot, std::move(pieces));
      entry.built[key] = object->geometry_stamp;
    }
  }
}

// Culls one level (objects, or sub-objects of k triangles) with three axis views, each with
// projection bounds recomputed from the primitives still alive. `alive` is in/out.
Result<void> GpuCuller::CullLevel(RendererEntry& entry, const StepRequest& request,
                                  std::span<const ViewObject> view_objects, int k,
                                  std::span<const Eigen::AlignedBox3d> primitive_boxes_W,
                                  std::vector<uint8_t>& alive, StepStats& stats, double* radius) {
  const std::vector<PieceSet> sets = PieceSetsFor(request.method);
  for (int axis = 0; axis < 3; ++axis) {
    // A primitive can only be kept by another group: stop when one group or none is left.
    std::set<uint32_t> groups;
    Eigen::AlignedBox3d bounds;
    int live = 0;
    for (const ViewObject& object : view_objects) {
      for (uint32_t j = 0; j < PrimitivesOf(object, k); ++j) {
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
    view.projection =
        ComputeProjection(bounds, entry.renderer->raster(), request.distance.value_or(0.0));
    view.objects = view_objects;
    view.triangles_per_primitive = k;
    view.num_primitives = static_cast<int>(alive.size());
    view.alive = alive;
    view.sets = sets;
    RenderCounters counters;
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

Result<std::vector<uint8_t>> GpuCuller::CullObjects(const StepRequest& request,
                                                    std::span<const CachedObject* const> objects,
                                                    StepStats& stats) {
  auto entry = RendererFor(request);
  if (!entry.ok()) return entry.error();
  const std::vector<PieceSet> sets = PieceSetsFor(request.method);
  EnsurePieces(**entry, objects, sets);
  // One primitive per object; each object is its own group.
  std::vector<ViewObject> view_objects;
  std::vector<Eigen::AlignedBox3d> boxes;
  for (size_t i = 0; i < objects.size(); ++i) {
    view_objects.push_back(
        MakeViewObject(*objects[i], static_cast<uint32_t>(i), static_cast<uint32_t>(i)));
    boxes.push_back(TransformBox(objects[i]->X_WM, objects[i]->rect_box_M));
  }
  std::vector<uint8_t> alive(objects.size(), 1);
  if (auto ok =
          CullLevel(**entry, request, view_objects, 0, boxes, alive, stats, &stats.object_radius);
      !ok.ok()) {
    return ok.error();
  }
  return alive;
}

Result<std::vector<std::vector<uint32_t>>> GpuCuller::CullPrimitives(
    const StepRequest& request, std::span<const CachedObject* const> objects,
    std::span<const size_t> paired, StepStats& stats) {
  auto entry = RendererFor(request);
  if (!entry.ok()) return entry.error();
  EnsurePieces(**entry, objects, PieceSetsFor(request.method));
  // Sub-objects of k triangles of the paired objects, each object its own group.
  const int k = request.subobject_size;
  std::vector<ViewObject> view_objects;
  std::vector<Eigen::AlignedBox3d> boxes;
  for (size_t i : paired) {
    const CachedObject& object = *objects[i];
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
  if (auto ok = CullLevel(**entry, request, view_objects, k, boxes, alive, stats,
                          &stats.primitive_radius);
      !ok.ok()) {
    return ok.error();
  }
  // Surviving sub-objects back to triangle indices, per object.
  std::vector<std::vector<uint32_t>> subsets(objects.size());
  for (const ViewObject& view : view_objects) {
    for (uint32_t j = 0; j < PrimitivesOf(view, k); ++j) {
      if (!alive[view.first_primitive + j]) continue;
      for (uint32_t t = j * k; t < std::min(view.num_triangles, (j + 1) * k); ++t)
        subsets[view.group].push_back(t);
    }
  }
  return subsets;
}

void GpuCuller::RemoveSlot(uint32_t slot) {
  for (auto& [key, entry] : renderers_) {
    entry.renderer->RemoveSlot(slot);
    for (int set = 0; set < kNumPieceSets; ++set) entry.built.erase({slot, set});
  }
}

}  // namespace far::internal
