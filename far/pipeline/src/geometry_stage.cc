#include "geometry_stage.h"

#include <cstdint>
#include <optional>
#include <unordered_map>
#include <utility>

#include "far/geometry/triangle_contact.h"
#include "far/pairs/penetration.h"

namespace far::internal {
namespace {

// Contacts and distance pairs are split into chunks of this many pairs across the pool: each
// pair costs well under a microsecond, so smaller chunks would cost more to hand out than to
// run, and larger ones would leave threads idle at the end of a few thousand contacts.
constexpr size_t kPairsPerChunk = 512;

TrianglePoints Triangle(const WorldObjectView& view, uint32_t triangle) {
  const TriangleIndices& v = view.triangles[triangle];
  return TrianglePoints{view.p_WV[v[0]], view.p_WV[v[1]], view.p_WV[v[2]]};
}

}  // namespace

bool ClosednessCache::IsClosed(size_t slot_index, std::span<const TriangleIndices> triangles,
                               size_t num_vertices) {
  if (slot_index >= closed_.size()) closed_.resize(slot_index + 1, -1);
  if (closed_[slot_index] < 0) closed_[slot_index] = IsClosedMesh(triangles, num_vertices) ? 1 : 0;
  return closed_[slot_index] == 1;
}

void ClosednessCache::Forget(size_t slot_index) {
  if (slot_index < closed_.size()) closed_[slot_index] = -1;
}

namespace {

// The step's object views by object id.
class ViewsById {
 public:
  ViewsById(std::span<const WorldObjectView> views, std::span<const uint32_t> id_of_slot)
      : views_(views) {
    for (size_t s = 0; s < views.size(); ++s) {
      if (!views[s].triangles.empty()) slot_of_id_[id_of_slot[s]] = s;
    }
  }
  size_t slot(uint32_t id) const { return slot_of_id_.at(id); }
  const WorldObjectView& operator()(uint32_t id) const { return views_[slot(id)]; }

 private:
  std::span<const WorldObjectView> views_;
  std::unordered_map<uint32_t, size_t> slot_of_id_;
};

// A pair's two triangles. Pairs come sorted by object pair: one reader per chunk looks each
// object up once per run of pairs.
class PairTriangles {
 public:
  explicit PairTriangles(const ViewsById& views) : views_(views) {}
  std::pair<TrianglePoints, TrianglePoints> operator()(const ContactPair& c) {
    if (c.object_a != a_) {
      a_ = c.object_a;
      view_a_ = &views_(a_);
    }
    if (c.object_b != b_) {
      b_ = c.object_b;
      view_b_ = &views_(b_);
    }
    return {Triangle(*view_a_, c.triangle_a), Triangle(*view_b_, c.triangle_b)};
  }

 private:
  const ViewsById& views_;
  uint32_t a_ = UINT32_MAX, b_ = UINT32_MAX;
  const WorldObjectView* view_a_ = nullptr;
  const WorldObjectView* view_b_ = nullptr;
};

// Each contact's geometry and each distance pair's closest points.
void PairGeometry(const ViewsById& views, ThreadPool& pool, StepResult& result) {
  result.contact_geometry.resize(result.contacts.size());
  pool.ParallelFor(result.contacts.size(), kPairsPerChunk, [&](size_t begin, size_t end) {
    PairTriangles triangles(views);
    for (size_t i = begin; i < end; ++i) {
      const auto [a, b] = triangles(result.contacts[i]);
      result.contact_geometry[i] = TriangleContactGeometry(a, b);
    }
  });
  result.closest_points.resize(result.distance_pairs.size());
  pool.ParallelFor(result.distance_pairs.size(), kPairsPerChunk, [&](size_t begin, size_t end) {
    PairTriangles triangles(views);
    for (size_t i = begin; i < end; ++i) {
      const auto [a, b] = triangles(result.distance_pairs[i].pair);
      // The exact stage reports 0 for intersecting pairs and only for them.
      result.closest_points[i] = result.distance_pairs[i].distance > 0
                                     ? DisjointClosestPoints(a, b)
                                     : TriangleClosestPoints(a, b);
    }
  });
}

// One penetration per object pair with contacts; measured where both objects are closed.
void Penetrations(std::span<const WorldObjectView> slots, const ViewsById& views, ThreadPool& pool,
                  ClosednessCache& closedness, StepResult& result) {
  // The pairs and where their contacts start (contacts are sorted by object pair).
  std::vector<ObjectPair> pairs;
  std::vector<size_t> first_contact;
  for (size_t i = 0; i < result.contacts.size(); ++i) {
    const ContactPair& c = result.contacts[i];
    if (pairs.empty() || pairs.back() != ObjectPair{c.object_a, c.object_b}) {
      pairs.push_back({c.object_a, c.object_b});
      first_contact.push_back(i);
    }
  }
  first_contact.push_back(result.contacts.size());
  // Closedness first, on this thread (the cache is not thread-safe); then one surface per
  // closed object in a pair of closed objects, shared by its pairs.
  std::vector<char> pair_closed(pairs.size());
  std::unordered_map<uint32_t, size_t> surface_of_id;
  std::vector<uint32_t> surface_ids;
  for (size_t i = 0; i < pairs.size(); ++i) {
    const size_t a = views.slot(pairs[i].object_a), b = views.slot(pairs[i].object_b);
    pair_closed[i] = closedness.IsClosed(a, slots[a].triangles, slots[a].p_WV.size()) &&
                     closedness.IsClosed(b, slots[b].triangles, slots[b].p_WV.size());
    if (!pair_closed[i]) continue;
    for (uint32_t id : {pairs[i].object_a, pairs[i].object_b}) {
      if (surface_of_id.emplace(id, surface_ids.size()).second) surface_ids.push_back(id);
    }
  }
  std::vector<std::optional<PenetrationSurface>> surfaces(surface_ids.size());
  pool.ParallelFor(surface_ids.size(), 1, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) surfaces[i].emplace(views(surface_ids[i]));
  });
  result.penetrations.resize(pairs.size());
  pool.ParallelFor(pairs.size(), 1, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      Penetration& p = result.penetrations[i];
      if (pair_closed[i]) {
        const std::span<const ContactPair> contacts(result.contacts.data() + first_contact[i],
                                                    first_contact[i + 1] - first_contact[i]);
        p = MeasurePenetration(*surfaces[surface_of_id.at(pairs[i].object_a)],
                               *surfaces[surface_of_id.at(pairs[i].object_b)], contacts);
      }
      p.object_a = pairs[i].object_a;
      p.object_b = pairs[i].object_b;
    }
  });
}

}  // namespace

void ComputeGeometry(std::span<const WorldObjectView> views, std::span<const uint32_t> id_of_slot,
                     ThreadPool& pool, ClosednessCache& closedness, StepResult& result) {
  const ViewsById by_id(views, id_of_slot);
  PairGeometry(by_id, pool, result);
  Penetrations(views, by_id, pool, closedness, result);
}

}  // namespace far::internal
