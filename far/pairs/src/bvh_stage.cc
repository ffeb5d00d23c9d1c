#include "far/pairs/bvh_stage.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstdint>

#include "triangle_pair_test.h"

// Why the descent never drops a pair the exact predicates accept. The exact stage tests the
// world vertices p_WV = fl(X_WM p_MV). A node's box holds its triangles' p_MV exactly, so the
// exactly transformed triangles lie in the node's box moved by X_WM (an oriented box). Each
// rounded world vertex is within delta <= 8 eps (sqrt(3) |p_M| + |t|) of its exact image
// (eps = 2^-53: three products and sums per coordinate). Two rounded triangles the predicates
// accept are within D + err (TrianglesWithinDistance's bound, inside DistanceSlack), so their
// exact images are within D + err + 2 delta, and so are the two oriented boxes: no separating
// axis can show a larger gap. The test below compares the gap along the face axes of both boxes
// with margin = slack + 2^-40 (the boxes' and poses' magnitudes), which also covers the
// rounding of the relative pose and of the test itself (tens of eps of the same magnitudes,
// far below 2^-40 = 8192 eps).

namespace far {
namespace {

using internal::BoxesWithin;
using internal::BoxOf;
using internal::Partial;
using internal::TestTrianglePair;
using internal::TriangleBox;
using internal::Wanted;
using Node = TriangleBvh::Node;

// The relative pose of a pair, prepared once: B's boxes into A's frame and A's into B's.
struct PairFrame {
  uint32_t a = 0, b = 0;  // indices into the query's objects, a has the smaller id
  Eigen::Matrix3d R_AB, abs_R_AB, R_BA, abs_R_BA;
  Eigen::Vector3d t_AB, t_BA;
  double margin = 0;
  // Both frames have the same rotation (static, deformable and unrotated objects): B's boxes
  // are A's boxes translated, and the test along A's axes is the whole test.
  bool aligned = false;
};

// max |coordinate| of a node box.
double BoxMagnitude(const Node& node) {
  return (node.center.cwiseAbs() + node.half_extent).maxCoeff();
}

PairFrame MakePairFrame(const BvhObject& a, const BvhObject& b, uint32_t ia, uint32_t ib,
                        double slack) {
  PairFrame f;
  f.a = ia;
  f.b = ib;
  const Eigen::Matrix3d R_AW = a.X_WM.linear().transpose();
  f.R_AB = R_AW * b.X_WM.linear();
  f.t_AB = R_AW * (b.X_WM.translation() - a.X_WM.translation());
  f.R_BA = f.R_AB.transpose();
  f.t_BA = -(f.R_BA * f.t_AB);
  f.abs_R_AB = f.R_AB.cwiseAbs();
  f.abs_R_BA = f.R_BA.cwiseAbs();
  f.aligned = a.X_WM.linear() == b.X_WM.linear();
  const double scale = 2 * (BoxMagnitude(a.bvh->nodes()[0]) + BoxMagnitude(b.bvh->nodes()[0])) +
                       a.X_WM.translation().cwiseAbs().maxCoeff() +
                       b.X_WM.translation().cwiseAbs().maxCoeff();
  f.margin = slack + 0x1p-40 * scale;
  return f;
}

// A pair of nodes still to descend, each node's box also moved into the other's frame (so that
// descending one node reuses the other's).
struct Task {
  uint32_t frame;
  uint32_t x, y;               // node of A, node of B
  Eigen::Vector3d cy_A, ey_A;  // y's box in A's frame (center, half extents)
  Eigen::Vector3d cx_B, ex_B;  // x's box in B's frame
};

void MoveIntoA(const PairFrame& f, const Node& y, Task& t) {
  if (f.aligned) {
    t.cy_A = y.center + f.t_AB;
    t.ey_A = y.half_extent;
  } else {
    t.cy_A = f.R_AB * y.center + f.t_AB;
    t.ey_A = f.abs_R_AB * y.half_extent;
  }
}
void MoveIntoB(const PairFrame& f, const Node& x, Task& t) {
  if (f.aligned) return;  // not needed: OverlapInB passes
  t.cx_B = f.R_BA * x.center + f.t_BA;
  t.ex_B = f.abs_R_BA * x.half_extent;
}

// The gap tests of a task's two boxes: no gap larger than the margin along A's three axes (with
// y moved into A) ...
bool OverlapInA(const PairFrame& f, const Node& x, const Task& t) {
  const Eigen::Array3d gap = (x.center - t.cy_A).array().abs() - (x.half_extent + t.ey_A).array();
  return !(gap > f.margin).any();
}
// ... nor along B's three (with x moved into B). Together: a conservative overlap test.
bool OverlapInB(const PairFrame& f, const Node& y, const Task& t) {
  if (f.aligned) return true;  // the same axes as A's
  const Eigen::Array3d gap = (y.center - t.cx_B).array().abs() - (y.half_extent + t.ex_B).array();
  return !(gap > f.margin).any();
}

double NodeSize(const Node& n) { return n.half_extent.sum(); }

// One chunk's output: the exact answers.
struct Output {
  Partial partial;
  size_t considered = 0;
};

// Everything a descent reads, and the candidate marks every thread writes: per object, per
// triangle, 1 when it met a partner's triangle (relaxed atomic stores of the same value).
struct Descent {
  const BvhQuery& query;
  const std::vector<PairFrame>& frames;
  const Wanted& wanted;
  std::vector<std::vector<uint8_t>>& marks;  // empty when candidates are not asked for

  void Mark(uint32_t object, uint32_t triangle) const {
    std::atomic_ref<uint8_t>(marks[object][triangle]).store(1, std::memory_order_relaxed);
  }
};

// The triangle pairs of two overlapping leaves: world boxes, prefilter, exact tests.
void TestLeaves(const Descent& d, const PairFrame& f, const Node& x, const Node& y, Output& out) {
  const BvhObject& a = d.query.objects[f.a];
  const BvhObject& b = d.query.objects[f.b];
  TriangleBox boxes_a[TriangleBvh::kLeafSize], boxes_b[TriangleBvh::kLeafSize];
  for (uint32_t i = 0; i < x.count; ++i) boxes_a[i] = BoxOf(a.world, a.bvh->order()[x.first + i]);
  for (uint32_t j = 0; j < y.count; ++j) boxes_b[j] = BoxOf(b.world, b.bvh->order()[y.first + j]);
  out.considered += size_t{x.count} * y.count;
  for (uint32_t i = 0; i < x.count; ++i) {
    for (uint32_t j = 0; j < y.count; ++j) {
      if (!BoxesWithin(boxes_a[i], boxes_b[j], d.wanted.slack)) continue;
      if (!d.marks.empty()) {
        d.Mark(f.a, boxes_a[i].triangle);
        d.Mark(f.b, boxes_b[j].triangle);
      }
      if (d.query.run_exact) {
        TestTrianglePair(a.world, boxes_a[i], b.world, boxes_b[j], d.wanted, out.partial);
      }
    }
  }
}

// Descends an overlapping task one level: the children pairs of its bigger node (the inner one
// when the other is a leaf) that overlap too are tested as leaves or pushed onto `next`.
void Expand(const Descent& d, const Task& task, std::vector<Task>& next, Output& out) {
  const PairFrame& f = d.frames[task.frame];
  const auto& nodes_a = d.query.objects[f.a].bvh->nodes();
  const auto& nodes_b = d.query.objects[f.b].bvh->nodes();
  const Node& x = nodes_a[task.x];
  const Node& y = nodes_b[task.y];
  const bool split_x = y.leaf() || (!x.leaf() && NodeSize(x) >= NodeSize(y));
  for (uint32_t child : {split_x ? x.first : y.first, (split_x ? x.first : y.first) + 1}) {
    // The kept node's box is already in the other frame: test that side first, and move the
    // child only when it passes.
    Task t = task;
    if (split_x) {
      t.x = child;
      if (!OverlapInA(f, nodes_a[child], t)) continue;
      MoveIntoB(f, nodes_a[child], t);
      if (!OverlapInB(f, y, t)) continue;
    } else {
      t.y = child;
      if (!OverlapInB(f, nodes_b[child], t)) continue;
      MoveIntoA(f, nodes_b[child], t);
      if (!OverlapInA(f, x, t)) continue;
    }
    const Node& cx = nodes_a[t.x];
    const Node& cy = nodes_b[t.y];
    if (cx.leaf() && cy.leaf()) {
      TestLeaves(d, f, cx, cy, out);
    } else {
      next.push_back(t);
    }
  }
}

// The descent of an aligned pair (same rotation: boxes differ by a translation only), with
// small tasks: the plain box test along the shared axes.
void DescendAligned(const Descent& d, const PairFrame& f, uint32_t root_x, uint32_t root_y,
                    Output& out) {
  const auto& nodes_a = d.query.objects[f.a].bvh->nodes();
  const auto& nodes_b = d.query.objects[f.b].bvh->nodes();
  const auto overlap = [&](const Node& x, const Node& y) {
    const Eigen::Array3d gap =
        (x.center - y.center - f.t_AB).array().abs() - (x.half_extent + y.half_extent).array();
    return !(gap > f.margin).any();
  };
  std::vector<std::pair<uint32_t, uint32_t>> stack = {{root_x, root_y}};
  for (uint32_t visited = 0; !stack.empty(); ++visited) {
    if (visited % 256 == 255 && d.wanted.stopper->Poll()) return;
    const auto [ix, iy] = stack.back();
    stack.pop_back();
    const Node& x = nodes_a[ix];
    const Node& y = nodes_b[iy];
    const bool split_x = y.leaf() || (!x.leaf() && NodeSize(x) >= NodeSize(y));
    const uint32_t first = split_x ? x.first : y.first;
    for (uint32_t child : {first, first + 1}) {
      const uint32_t cx = split_x ? child : ix, cy = split_x ? iy : child;
      if (!overlap(nodes_a[cx], nodes_b[cy])) continue;
      if (nodes_a[cx].leaf() && nodes_b[cy].leaf()) {
        TestLeaves(d, f, nodes_a[cx], nodes_b[cy], out);
      } else {
        stack.emplace_back(cx, cy);
      }
    }
  }
}

// Depth-first descent of one overlapping task to its leaves.
void Descend(const Descent& d, const Task& root, Output& out) {
  const PairFrame& f = d.frames[root.frame];
  if (f.aligned) return DescendAligned(d, f, root.x, root.y, out);
  std::vector<Task> stack = {root};
  for (uint32_t visited = 0; !stack.empty(); ++visited) {
    if (visited % 256 == 255 && d.wanted.stopper->Poll()) return;
    const Task task = stack.back();
    stack.pop_back();
    Expand(d, task, stack, out);
  }
}

// The object pairs as frames (indices into objects, smaller id first, each once).
std::vector<PairFrame> MakeFrames(const BvhQuery& query, double slack) {
  std::vector<std::pair<uint32_t, uint32_t>> id_index(query.objects.size());
  for (uint32_t i = 0; i < query.objects.size(); ++i) id_index[i] = {query.objects[i].world.id, i};
  std::sort(id_index.begin(), id_index.end());
  auto index_of = [&](uint32_t id) -> int64_t {
    auto it = std::lower_bound(id_index.begin(), id_index.end(), std::make_pair(id, 0u));
    return it != id_index.end() && it->first == id ? it->second : -1;
  };
  std::vector<PairFrame> frames;
  for (const ObjectPair& pair : query.object_pairs) {
    const int64_t a = index_of(std::min(pair.object_a, pair.object_b));
    const int64_t b = index_of(std::max(pair.object_a, pair.object_b));
    assert(a >= 0 && b >= 0 && a != b);
    if (a < 0 || b < 0 || a == b) continue;
    const BvhObject& oa = query.objects[static_cast<size_t>(a)];
    const BvhObject& ob = query.objects[static_cast<size_t>(b)];
    if (oa.bvh == nullptr || ob.bvh == nullptr || oa.bvh->empty() || ob.bvh->empty()) continue;
    frames.push_back(
        MakePairFrame(oa, ob, static_cast<uint32_t>(a), static_cast<uint32_t>(b), slack));
  }
  std::sort(frames.begin(), frames.end(), [](const PairFrame& x, const PairFrame& y) {
    return std::tie(x.a, x.b) < std::tie(y.a, y.b);
  });
  frames.erase(
      std::unique(frames.begin(), frames.end(),
                  [](const PairFrame& x, const PairFrame& y) { return x.a == y.a && x.b == y.b; }),
      frames.end());
  return frames;
}

// The overlapping root pairs, expanded breadth-first until there are enough tasks to share among
// threads; leaves met on the way are tested into `out`.
std::vector<Task> SeedTasks(const Descent& d, size_t target, Output& out) {
  std::vector<Task> tasks;
  for (uint32_t i = 0; i < d.frames.size(); ++i) {
    const PairFrame& f = d.frames[i];
    const Node& x = d.query.objects[f.a].bvh->nodes()[0];
    const Node& y = d.query.objects[f.b].bvh->nodes()[0];
    Task root{i, 0, 0, {}, {}, {}, {}};
    MoveIntoA(f, y, root);
    MoveIntoB(f, x, root);
    if (!OverlapInA(f, x, root) || !OverlapInB(f, y, root)) continue;
    if (x.leaf() && y.leaf()) {
      TestLeaves(d, f, x, y, out);
    } else {
      tasks.push_back(root);
    }
  }
  while (!tasks.empty() && tasks.size() < target) {
    std::vector<Task> next;
    for (const Task& task : tasks) Expand(d, task, next, out);
    const bool growing = next.size() > tasks.size();
    tasks = std::move(next);
    if (!growing) break;  // mostly leaves left: descend what there is
  }
  return tasks;
}

// The largest |coordinate| of the world vertices of the paired objects (for DistanceSlack).
double WorldMagnitude(const BvhQuery& query, const std::vector<PairFrame>& frames) {
  std::vector<uint8_t> used(query.objects.size(), 0);
  for (const PairFrame& f : frames) used[f.a] = used[f.b] = 1;
  double magnitude = 0;
  for (size_t o = 0; o < used.size(); ++o) {
    if (!used[o]) continue;
    for (const Eigen::Vector3d& p : query.objects[o].world.p_WV)
      magnitude = std::max(magnitude, p.cwiseAbs().maxCoeff());
  }
  return magnitude;
}

}  // namespace

BvhResult RunBvhTests(const BvhQuery& query, ThreadPool& pool) {
  // The distance widens the search (candidates within it) even when no distance pair is asked.
  internal::Stopper stopper(query.control);
  Wanted wanted;
  wanted.contacts = query.want_contacts;
  wanted.stopper = &stopper;
  const bool within = query.max_distance.has_value() && *query.max_distance >= 0;
  wanted.distance = within && query.want_distance_pairs;
  std::vector<PairFrame> frames = MakeFrames(query, 0);
  if (within) {
    wanted.max_distance = *query.max_distance;
    wanted.slack = internal::DistanceSlack(wanted.max_distance, WorldMagnitude(query, frames));
    frames = MakeFrames(query, wanted.slack);
  }
  std::vector<std::vector<uint8_t>> marks;
  if (query.want_candidates) {
    marks.resize(query.objects.size());
    for (const PairFrame& f : frames) {
      marks[f.a].resize(query.objects[f.a].world.triangles.size(), 0);
      marks[f.b].resize(query.objects[f.b].world.triangles.size(), 0);
    }
  }
  const Descent descent{query, frames, wanted, marks};

  // Seed tasks on this thread, then descend them on the pool.
  const size_t threads = static_cast<size_t>(pool.num_threads());
  std::vector<Output> outputs(1);
  const std::vector<Task> tasks = SeedTasks(descent, 64 * threads, outputs[0]);
  const size_t grain = std::clamp<size_t>(tasks.size() / (16 * threads), 1, 256);
  outputs.resize(1 + (tasks.size() + grain - 1) / grain);
  pool.ParallelFor(tasks.size(), grain, [&](size_t begin, size_t end) {
    Output& out = outputs[1 + begin / grain];
    for (size_t i = begin; i < end && !stopper.Poll(); ++i) Descend(descent, tasks[i], out);
  });

  // Merge: sorted answers and candidates, whatever the number of threads.
  BvhResult result;
  std::vector<Partial> partials;
  size_t considered = 0;
  for (Output& out : outputs) {
    considered += out.considered;
    partials.push_back(std::move(out.partial));
  }
  result.candidates.resize(marks.size());
  for (size_t o = 0; o < marks.size(); ++o) {
    for (uint32_t t = 0; t < marks[o].size(); ++t) {
      if (marks[o][t]) result.candidates[o].push_back(t);
    }
  }
  result.exact = internal::Merge(partials, considered, &stopper);
  if (result.exact.stopped != StopReason::kNone) result.candidates.clear();
  return result;
}

}  // namespace far
