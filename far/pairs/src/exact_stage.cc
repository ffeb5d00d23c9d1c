#include "far/pairs/exact_stage.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "triangle_pair_test.h"

#include "far/base/assert.h"

// The exact stage: for every candidate object pair, the candidate triangles of one object against
// those of the other, an AABB prefilter, then the exact predicates (triangle_pair_test.h says
// why the prefilter never rejects a pair the predicates would accept).
//
// Pair finding between two triangle lists is a one-axis sort-and-sweep: each object's candidate
// triangle boxes are built and sorted by their x minimum once per call, then every triangle looks
// forward in the other list from its own x minimum until the x gap exceeds the slack. A pair is
// met exactly once (by whichever of the two starts first in x; ties go to the first object). For
// lists of n and m triangles the cost is O((n + m) log(n + m) + k_x) with k_x the pairs that
// overlap in x, instead of O(n m) box tests.
//
// The work is split into items (a range of one list's triangles of one object pair) that run on
// the thread pool and fill their own output vectors; these are concatenated and sorted, so the
// output does not depend on the number of threads.

namespace far {
namespace {

using internal::BoxesWithin;
using internal::BoxOf;
using internal::DistanceSlack;
using internal::Merge;
using internal::PairedSlots;
using internal::Partial;
using internal::SlotView;
using internal::TestTrianglePair;
using internal::TriangleBox;
using internal::Wanted;

// The candidate triangles of one object, sorted by lo[0].
using SortedBoxes = std::vector<TriangleBox>;

// The largest absolute corner coordinate of the given triangles (0 if none).
double Magnitude(std::span<const TriangleBox> boxes) {
  double magnitude = 0;
  for (const TriangleBox& box : boxes) {
    for (int axis = 0; axis < 3; ++axis) {
      magnitude = std::max({magnitude, std::abs(box.lo[axis]), std::abs(box.hi[axis])});
    }
  }
  return magnitude;
}

// A range of one side's triangles of one object pair: each looks forward in the other side.
struct WorkItem {
  ObjectSlot object_a;  // the smaller slot
  ObjectSlot object_b;  // the larger slot
  bool from_b;          // the range is of object_b's list (else of object_a's)
  uint32_t begin, end;
};

// Runs one work item: every triangle of the range meets the other side's triangles that start at
// or after it in x (strictly after when it is object_b's, so that ties are met once, from a) and
// within the slack of its x maximum.
void RunItem(const WorkItem& item, std::span<const WorldObjectView> objects,
             const std::vector<SortedBoxes>& boxes, const Wanted& wanted, Partial& out,
             StepStopper& stopper) {
  const SlotView object_a{item.object_a, objects[Index(item.object_a)]};
  const SlotView object_b{item.object_b, objects[Index(item.object_b)]};
  const SortedBoxes& own = boxes[Index(item.from_b ? item.object_b : item.object_a)];
  const SortedBoxes& other = boxes[Index(item.from_b ? item.object_a : item.object_b)];
  // The first candidate in `other` for the range's first triangle; it only moves forward.
  const auto starts_before = [&](const TriangleBox& o, double lo) {
    return item.from_b ? o.lo[0] <= lo : o.lo[0] < lo;
  };
  size_t first =
      static_cast<size_t>(std::partition_point(other.begin(), other.end(),
                                               [&](const TriangleBox& o) {
                                                 return starts_before(o, own[item.begin].lo[0]);
                                               }) -
                          other.begin());
  for (uint32_t i = item.begin; i < item.end; ++i) {
    // Cancellation: the clock every 16 triangles, the shared flag at every one.
    if ((i - item.begin) % 16 == 0 ? stopper.Poll() : stopper.stopped()) return;
    const TriangleBox& mine = own[i];
    while (first < other.size() && starts_before(other[first], mine.lo[0])) ++first;
    for (size_t k = first; k < other.size() && other[k].lo[0] - mine.hi[0] <= wanted.slack; ++k) {
      // (a huge distance D makes one triangle meet a whole list)
      if ((k - first) % 4096 == 4095 && stopper.Poll()) return;
      if (!BoxesWithin(mine, other[k], wanted.slack)) continue;
      if (item.from_b) {
        TestTrianglePair(object_a, other[k], object_b, mine, wanted, out);
      } else {
        TestTrianglePair(object_a, mine, object_b, other[k], wanted, out);
      }
    }
  }
}

// Each side of an object pair is cut into ranges of this many triangles, a work item each.
constexpr uint32_t kItemTriangles = 512;

// Triangles between two polls of the stopper while boxes are made.
constexpr uint32_t kBoxesPerPoll = 1 << 15;

// The candidate triangle boxes of the object in slot `o` (its subset, each valid triangle once),
// sorted by their low x. Empty when the stopper stopped it.
SortedBoxes CandidateBoxes(const ExactQuery& query, size_t o, StepStopper& stopper) {
  const WorldObjectView& object = query.objects[o];
  const auto num_triangles = static_cast<uint32_t>(object.triangles.size());
  SortedBoxes list;
  if (query.triangle_subsets.empty() || o >= query.triangle_subsets.size()) {
    list.reserve(num_triangles);
    for (uint32_t t = 0; t < num_triangles; ++t) {
      if (t % kBoxesPerPoll == kBoxesPerPoll - 1 && stopper.Poll()) return {};
      list.push_back(BoxOf(object, t));
    }
  } else {
    std::vector<uint32_t> subset = query.triangle_subsets[o];
    std::sort(subset.begin(), subset.end());
    subset.erase(std::unique(subset.begin(), subset.end()), subset.end());
    FAR_ASSERT(subset.empty() || subset.back() < num_triangles, "a subset of the triangles");
    list.reserve(subset.size());
    for (uint32_t t : subset) {
      if (t < num_triangles) list.push_back(BoxOf(object, t));
    }
  }
  if (stopper.Poll()) return {};
  std::sort(list.begin(), list.end(), [](const TriangleBox& x, const TriangleBox& y) {
    return x.lo[0] < y.lo[0] || (x.lo[0] == y.lo[0] && x.triangle < y.triangle);
  });
  return list;
}

// Cuts every object pair into work items of about kItemTriangles triangles; counts the
// candidate triangle pairs.
std::vector<WorkItem> CutIntoItems(std::span<const SlotPair> pairs,
                                   const std::vector<SortedBoxes>& boxes,
                                   size_t* pairs_considered) {
  std::vector<WorkItem> items;
  for (const auto& [a, b] : pairs) {
    const auto size_a = static_cast<uint32_t>(boxes[Index(a)].size());
    const auto size_b = static_cast<uint32_t>(boxes[Index(b)].size());
    *pairs_considered += static_cast<size_t>(size_a) * size_b;
    if (size_a == 0 || size_b == 0) continue;
    for (bool from_b : {false, true}) {
      const uint32_t size = from_b ? size_b : size_a;
      for (uint32_t begin = 0; begin < size; begin += kItemTriangles) {
        items.push_back({a, b, from_b, begin, std::min(size, begin + kItemTriangles)});
      }
    }
  }
  return items;
}

}  // namespace

ExactResult RunExactTests(const ExactQuery& query, ThreadPool& pool) {
  const std::span<const WorldObjectView> objects = query.objects;
  FAR_ASSERT(query.triangle_subsets.empty() || query.triangle_subsets.size() == objects.size(),
             "subsets indexed like the objects");

  // Build and sort the candidate triangle boxes of every object in some pair, once.
  const std::vector<ObjectSlot> used = PairedSlots(query);
  std::vector<SortedBoxes> boxes(objects.size());
  StepStopper stopper(query.control);
  pool.ParallelFor(used.size(), 1, [&](size_t begin, size_t end) {
    for (size_t u = begin; u < end && !stopper.Poll(); ++u)
      boxes[Index(used[u])] = CandidateBoxes(query, Index(used[u]), stopper);
  });
  if (stopper.stopped()) {
    std::vector<Partial> none;
    return Merge(none, 0, &stopper);  // stopped: no answer
  }

  // Decide what to compute and the prefilter slack. A negative or NaN max_distance finds nothing.
  Wanted wanted;
  wanted.distance =
      query.want_distance_pairs && query.max_distance.has_value() && *query.max_distance >= 0;
  wanted.stopper = &stopper;
  if (wanted.distance) {
    wanted.max_distance = *query.max_distance;
    double magnitude = 0;
    for (ObjectSlot o : used) magnitude = std::max(magnitude, Magnitude(boxes[Index(o)]));
    wanted.slack = DistanceSlack(wanted.max_distance, magnitude);
  }
  size_t pairs_considered = 0;
  const std::vector<WorkItem> items = CutIntoItems(query.object_pairs, boxes, &pairs_considered);

  // Run the items on the pool, each chunk of items into its own output.
  const size_t threads = static_cast<size_t>(pool.num_threads());
  const size_t grain = std::clamp<size_t>(items.size() / (8 * threads), 1, 64);
  std::vector<Partial> partials((items.size() + grain - 1) / grain);
  pool.ParallelFor(items.size(), grain, [&](size_t begin, size_t end) {
    Partial& out = partials[begin / grain];
    for (size_t i = begin; i < end && !stopper.stopped(); ++i)
      RunItem(items[i], objects, boxes, wanted, out, stopper);
  });
  return Merge(partials, pairs_considered, &stopper);
}

ExactResult RunExactTestsOnPairs(const TrianglePairQuery& query, ThreadPool& pool) {
  FAR_ASSERT(query.known_apart.empty() || query.known_apart.size() == query.pairs.size(),
             "known_apart indexed like the pairs");
  for (const SlotContact& pair : query.pairs) {
    FAR_DEMAND(Index(pair.object_a) < query.objects.size() &&
                   Index(pair.object_b) < query.objects.size() &&
                   pair.triangle_a < query.objects[Index(pair.object_a)].triangles.size() &&
                   pair.triangle_b < query.objects[Index(pair.object_b)].triangles.size(),
               "triangle pairs of the query's objects");
  }
  StepStopper stopper(query.control);
  const bool distance =
      query.want_distance_pairs && query.max_distance.has_value() && *query.max_distance >= 0;
  constexpr size_t kGrain = 256;
  std::vector<Partial> partials((query.pairs.size() + kGrain - 1) / kGrain);
  pool.ParallelFor(query.pairs.size(), kGrain, [&](size_t begin, size_t end) {
    Partial& out = partials[begin / kGrain];
    for (size_t i = begin; i < end && !stopper.Poll(); ++i) {
      const SlotContact& pair = query.pairs[i];
      const SlotView a{pair.object_a, query.objects[Index(pair.object_a)]};
      const SlotView b{pair.object_b, query.objects[Index(pair.object_b)]};
      const TriangleBox box_a = BoxOf(a.view, pair.triangle_a);
      const TriangleBox box_b = BoxOf(b.view, pair.triangle_b);
      // The slack of RunExactTests' prefilter, from these two triangles' coordinates: it
      // only needs to cover them (DistanceSlack), and TriangleDistanceIfWithin decides.
      Wanted wanted;
      wanted.stopper = &stopper;
      if (distance) {
        wanted.distance = true;
        wanted.max_distance = *query.max_distance;
        const TriangleBox two[] = {box_a, box_b};
        wanted.slack = DistanceSlack(wanted.max_distance, Magnitude(two));
      }
      if (!BoxesWithin(box_a, box_b, wanted.slack)) continue;
      const bool known_apart = !query.known_apart.empty() && query.known_apart[i] != 0;
      TestTrianglePair(a, box_a, b, box_b, wanted, out, known_apart);
    }
  });
  return Merge(partials, query.pairs.size(), &stopper);
}

std::vector<ObjectSlot> SlotsInPairs(std::span<const SlotPair> pairs) {
  std::vector<ObjectSlot> slots;
  slots.reserve(2 * pairs.size());
  for (const SlotPair& pair : pairs) slots.insert(slots.end(), {pair.object_a, pair.object_b});
  std::sort(slots.begin(), slots.end());
  slots.erase(std::unique(slots.begin(), slots.end()), slots.end());
  return slots;
}

uint64_t BruteForcePairs(std::span<const WorldObjectView> objects) {
  // sum over i of n_i times the triangles before it, saturating at UINT64_MAX.
  uint64_t pairs = 0, before = 0;
  for (const WorldObjectView& object : objects) {
    const uint64_t n = object.triangles.size();
    uint64_t product = 0;
    if (__builtin_mul_overflow(n, before, &product) ||
        __builtin_add_overflow(pairs, product, &pairs)) {
      return UINT64_MAX;
    }
    before += n;
  }
  return pairs;
}

ExactResult BruteForceReference(std::span<const WorldObjectView> objects,
                                std::optional<double> max_distance, ThreadPool& pool,
                                const StepControl* control) {
  // Every triangle's box.
  std::vector<SortedBoxes> boxes(objects.size());
  double magnitude = 0;
  for (size_t o = 0; o < objects.size(); ++o) {
    for (uint32_t t = 0; t < objects[o].triangles.size(); ++t) {
      boxes[o].push_back(BoxOf(objects[o], t));
    }
    magnitude = std::max(magnitude, Magnitude(boxes[o]));
  }
  StepStopper stopper(control);
  Wanted wanted;
  wanted.distance = max_distance.has_value() && *max_distance >= 0;
  wanted.stopper = &stopper;
  if (wanted.distance) {
    wanted.max_distance = *max_distance;
    wanted.slack = DistanceSlack(wanted.max_distance, magnitude);
  }

  // Every object pair i < j, every triangle of i against every triangle of j.
  std::vector<Partial> partials;
  size_t pairs_considered = 0;
  constexpr size_t kGrain = 64;
  for (size_t i = 0; i < objects.size() && !stopper.stopped(); ++i) {
    for (size_t j = i + 1; j < objects.size() && !stopper.stopped(); ++j) {
      const SlotView a{SlotAt(i), objects[i]}, b{SlotAt(j), objects[j]};
      pairs_considered += boxes[i].size() * boxes[j].size();
      const size_t first = partials.size();
      partials.resize(first + (boxes[i].size() + kGrain - 1) / kGrain);
      pool.ParallelFor(boxes[i].size(), kGrain, [&](size_t begin, size_t end) {
        Partial& out = partials[first + begin / kGrain];
        for (size_t ta = begin; ta < end; ++ta) {
          if (stopper.Poll()) return;
          for (size_t tb = 0; tb < boxes[j].size(); ++tb) {
            if (!BoxesWithin(boxes[i][ta], boxes[j][tb], wanted.slack)) continue;
            TestTrianglePair(a, boxes[i][ta], b, boxes[j][tb], wanted, out);
          }
        }
      });
    }
  }
  return Merge(partials, pairs_considered, &stopper);
}

double CullSlack(double max_distance, double magnitude) {
  // DistanceSlack covers the predicate; 2^-50 = 8 ulps of (magnitude + limit) covers rounding
  // both sides of a box grown by it, with room to spare.
  return DistanceSlack(max_distance, magnitude) + 0x1p-50 * (magnitude + max_distance);
}

}  // namespace far
