// Measures the cost of one closed triangle-triangle intersection test: far::TrianglesIntersect
// (exact: orientation predicates with a floating-point filter and an exact fallback) against
// FCL 0.7's separating-axis test fcl::detail::Intersect<double>::intersect_Triangle (plain
// floating point), on the same pairs. Why: the exact stage runs this test on every candidate
// pair, and exactness must not cost speed. Run A and B interleaved with repetitions and compare
// medians (see bench/RESULTS.md for the command):
//   far_triangle_benchmark --benchmark_repetitions=20 --benchmark_enable_random_interleaving=true
// Pair sets (fixed seeds, 4096 pairs, cycled):
//   Random: all six vertices uniform in the unit cube (boxes nearly always overlap; 28% meet).
//   Close:  triangles of size ~0.1 with centers in a 0.05 cube, as candidate pairs look after
//           culling (boxes nearly always overlap; 24% meet).
//   Far:    the same triangles with centers in a unit cube (most boxes disjoint; 0.1% meet).
// Counters: per_pair (seconds per tested pair); for far, the fraction of pairs that meet
// ("meet"); for FCL, the fraction of pairs where it disagrees with far's exact answer
// ("disagree").
// The distance benchmarks time far::TriangleDistanceIfWithin (the distance pass's test: the
// distance of a pair within D, with a bounded error, else nothing) at D = 0.01 on the close and
// far sets, against FCL's plain floating-point TriangleDistance::triDistance, which always
// computes the distance ("within": the fraction far accepts).

#include <random>
#include <vector>

#include <benchmark/benchmark.h>
#include <fcl/narrowphase/detail/primitive_shape_algorithm/triangle_distance.h>
#include <fcl/narrowphase/detail/traversal/collision/intersect.h>

#include "far/geometry/triangle_tests.h"

namespace {

using Eigen::Vector3d;

struct Pair {
  far::TrianglePoints s, t;
};

enum class Kind { kRandom, kClose, kFar };

std::vector<Pair> MakePairs(Kind kind) {
  std::mt19937_64 rng(kind == Kind::kRandom ? 1 : kind == Kind::kClose ? 2 : 3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_real_distribution<double> local(-0.1, 0.1);
  const double spread = kind == Kind::kClose ? 0.05 : 1.0;
  const auto triangle = [&] {
    if (kind == Kind::kRandom) {
      return far::TrianglePoints{Vector3d(u(rng), u(rng), u(rng)), Vector3d(u(rng), u(rng), u(rng)),
                                 Vector3d(u(rng), u(rng), u(rng))};
    }
    const Vector3d center = spread * Vector3d(u(rng), u(rng), u(rng));
    const auto corner = [&] {
      return Vector3d(center + Vector3d(local(rng), local(rng), local(rng)));
    };
    return far::TrianglePoints{corner(), corner(), corner()};
  };
  std::vector<Pair> pairs(4096);
  for (Pair& p : pairs) {
    p.s = triangle();
    p.t = triangle();
  }
  return pairs;
}

const std::vector<Pair>& Pairs(Kind kind) {
  static const std::vector<Pair> random = MakePairs(Kind::kRandom);
  static const std::vector<Pair> close = MakePairs(Kind::kClose);
  static const std::vector<Pair> far_apart = MakePairs(Kind::kFar);
  return kind == Kind::kRandom ? random : kind == Kind::kClose ? close : far_apart;
}

bool FclIntersect(const Pair& p) {
  return fcl::detail::Intersect<double>::intersect_Triangle(p.s.a, p.s.b, p.s.c, p.t.a, p.t.b,
                                                            p.t.c);
}

// Adds "per_pair": seconds of CPU time per tested pair (printed with an SI prefix, e.g. 21.3n).
void Report(benchmark::State& state, size_t pairs_per_iteration) {
  const double pairs =
      static_cast<double>(state.iterations()) * static_cast<double>(pairs_per_iteration);
  state.counters["per_pair"] =
      benchmark::Counter(pairs, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void RunFar(benchmark::State& state, Kind kind) {
  const std::vector<Pair>& pairs = Pairs(kind);
  int hits = 0;
  for (auto _ : state) {
    for (const Pair& p : pairs) hits += far::TrianglesIntersect(p.s, p.t);
    benchmark::DoNotOptimize(hits);
  }
  Report(state, pairs.size());
  int meet = 0;
  for (const Pair& p : pairs) meet += far::TrianglesIntersect(p.s, p.t);
  state.counters["meet"] = static_cast<double>(meet) / static_cast<double>(pairs.size());
}

void RunFcl(benchmark::State& state, Kind kind) {
  const std::vector<Pair>& pairs = Pairs(kind);
  int hits = 0;
  for (auto _ : state) {
    for (const Pair& p : pairs) hits += FclIntersect(p);
    benchmark::DoNotOptimize(hits);
  }
  Report(state, pairs.size());
  int disagree = 0;
  for (const Pair& p : pairs) disagree += FclIntersect(p) != far::TrianglesIntersect(p.s, p.t);
  state.counters["disagree"] = static_cast<double>(disagree) / static_cast<double>(pairs.size());
}

void BM_FarTrianglesIntersect_Random(benchmark::State& state) { RunFar(state, Kind::kRandom); }
void BM_FclIntersectTriangle_Random(benchmark::State& state) { RunFcl(state, Kind::kRandom); }
void BM_FarTrianglesIntersect_Close(benchmark::State& state) { RunFar(state, Kind::kClose); }
void BM_FclIntersectTriangle_Close(benchmark::State& state) { RunFcl(state, Kind::kClose); }
void BM_FarTrianglesIntersect_Far(benchmark::State& state) { RunFar(state, Kind::kFar); }
void BM_FclIntersectTriangle_Far(benchmark::State& state) { RunFcl(state, Kind::kFar); }

constexpr double kDistance = 0.01;

void RunFarDistance(benchmark::State& state, Kind kind) {
  const std::vector<Pair>& pairs = Pairs(kind);
  double sum = 0;
  for (auto _ : state) {
    for (const Pair& p : pairs)
      sum += far::TriangleDistanceIfWithin(p.s, p.t, kDistance).value_or(0);
    benchmark::DoNotOptimize(sum);
  }
  Report(state, pairs.size());
  int within = 0;
  for (const Pair& p : pairs) within += far::TrianglesWithinDistance(p.s, p.t, kDistance);
  state.counters["within"] = static_cast<double>(within) / static_cast<double>(pairs.size());
}

void RunFclDistance(benchmark::State& state, Kind kind) {
  const std::vector<Pair>& pairs = Pairs(kind);
  double sum = 0;
  Vector3d closest_s, closest_t;
  for (auto _ : state) {
    for (const Pair& p : pairs) {
      sum += fcl::detail::TriangleDistance<double>::triDistance(p.s.a, p.s.b, p.s.c, p.t.a, p.t.b,
                                                                p.t.c, closest_s, closest_t);
    }
    benchmark::DoNotOptimize(sum);
  }
  Report(state, pairs.size());
}

void BM_FarTriangleDistanceIfWithin_Close(benchmark::State& state) {
  RunFarDistance(state, Kind::kClose);
}
void BM_FclTriangleDistance_Close(benchmark::State& state) { RunFclDistance(state, Kind::kClose); }
void BM_FarTriangleDistanceIfWithin_Far(benchmark::State& state) {
  RunFarDistance(state, Kind::kFar);
}
void BM_FclTriangleDistance_Far(benchmark::State& state) { RunFclDistance(state, Kind::kFar); }

BENCHMARK(BM_FarTrianglesIntersect_Random);
BENCHMARK(BM_FclIntersectTriangle_Random);
BENCHMARK(BM_FarTrianglesIntersect_Close);
BENCHMARK(BM_FclIntersectTriangle_Close);
BENCHMARK(BM_FarTrianglesIntersect_Far);
BENCHMARK(BM_FclIntersectTriangle_Far);
BENCHMARK(BM_FarTriangleDistanceIfWithin_Close);
BENCHMARK(BM_FclTriangleDistance_Close);
BENCHMARK(BM_FarTriangleDistanceIfWithin_Far);
BENCHMARK(BM_FclTriangleDistance_Far);

}  // namespace

BENCHMARK_MAIN();
