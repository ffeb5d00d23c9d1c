#pragma once

// Randomized pair generators for the triangle tests (fixed seeds, deterministic): generic
// random pairs, and grid-snapped pairs that force exact coplanarity, shared vertices, touching
// and degenerate triangles, at the origin and far from it.

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "far/geometry/triangle_tests.h"

namespace far::reference {

struct PairScene {
  std::string name;
  int count;
  std::function<std::pair<TrianglePoints, TrianglePoints>(std::mt19937_64&)> make;
};

inline std::vector<PairScene> MakePairScenes() {
  using Eigen::Vector3d;
  const auto tri = [](const std::function<Vector3d()>& point) {
    return TrianglePoints{point(), point(), point()};
  };
  std::vector<PairScene> scenes;
  // Generic doubles in the unit cube.
  scenes.push_back({"uniform", 20000, [tri](std::mt19937_64& rng) {
                      std::uniform_real_distribution<double> u(0.0, 1.0);
                      const auto p = [&] { return Vector3d(u(rng), u(rng), u(rng)); };
                      return std::make_pair(tri(p), tri(p));
                    }});
  // Small integer grid: many exactly coplanar, touching and degenerate pairs.
  scenes.push_back({"grid", 20000, [tri](std::mt19937_64& rng) {
                      std::uniform_int_distribution<int> k(0, 3);
                      const auto p = [&] { return Vector3d(k(rng), k(rng), k(rng)); };
                      return std::make_pair(tri(p), tri(p));
                    }});
  // Six vertices drawn from a pool of five grid points: shared vertices and edges, repeated
  // points, collinear and point triangles.
  scenes.push_back(
      {"shared_pool", 10000, [](std::mt19937_64& rng) {
         std::uniform_int_distribution<int> k(0, 2);
         std::vector<Vector3d> pool;
         for (int i = 0; i < 5; ++i) pool.emplace_back(k(rng), k(rng), k(rng));
         std::uniform_int_distribution<int> pick(0, 4);
         const auto p = [&] { return pool[pick(rng)]; };
         return std::make_pair(TrianglePoints{p(), p(), p()}, TrianglePoints{p(), p(), p()});
       }});
  // The grid at 1e6 with features of 2^-10 (about 1e-3), still exact.
  scenes.push_back({"grid_1e6", 10000, [tri](std::mt19937_64& rng) {
                      std::uniform_int_distribution<int> k(0, 3);
                      const double f = std::ldexp(1.0, -10);
                      const auto p = [&] {
                        return Vector3d(1e6 + f * k(rng), -1e6 + f * k(rng), 1e5 + f * k(rng));
                      };
                      return std::make_pair(tri(p), tri(p));
                    }});
  // The grid with coordinates nudged by one ulp at random: near-degenerate, near-touching
  // (the grid starts at 1 so that no nudge makes a subnormal number).
  scenes.push_back({"grid_ulp", 10000, [tri](std::mt19937_64& rng) {
                      std::uniform_int_distribution<int> k(1, 4);
                      std::uniform_int_distribution<int> nudge(-1, 1);
                      const auto c = [&] {
                        const double x = k(rng);
                        const int n = nudge(rng);
                        return n == 0 ? x : std::nextafter(x, n * HUGE_VAL);
                      };
                      const auto p = [&] { return Vector3d(c(), c(), c()); };
                      return std::make_pair(tri(p), tri(p));
                    }});
  // Points on the tilted plane z = x/2 + y/4 (exact), some lifted off it by one ulp.
  scenes.push_back({"tilted_plane", 10000, [tri](std::mt19937_64& rng) {
                      std::uniform_int_distribution<int> k(-3, 3);
                      std::uniform_int_distribution<int> lift(0, 7);
                      const auto p = [&] {
                        const double x = k(rng), y = k(rng);
                        double z = 1e5 + x / 2 + y / 4;
                        if (lift(rng) == 0) z = std::nextafter(z, HUGE_VAL);
                        return Vector3d(1e5 + x, y, z);
                      };
                      return std::make_pair(tri(p), tri(p));
                    }});
  // Generic doubles, t nearly in the plane of s (its vertices are rounded affine combinations of
  // s's): tiny orientations that only the exact fallback decides.
  scenes.push_back({"near_coplanar", 10000, [tri](std::mt19937_64& rng) {
                      std::uniform_real_distribution<double> u(0.0, 1.0);
                      std::uniform_real_distribution<double> w(-0.5, 1.5);
                      const auto p = [&] { return Vector3d(u(rng), u(rng), u(rng)); };
                      const TrianglePoints s = tri(p);
                      const auto q = [&] {
                        return Vector3d(s.a + w(rng) * (s.b - s.a) + w(rng) * (s.c - s.a));
                      };
                      return std::make_pair(s, tri(q));
                    }});
  // Generic doubles, a vertex of t on (the rounding of) a point of an edge of s, the rest of t
  // on one side or across: touching up to rounding.
  scenes.push_back({"near_touching", 10000, [tri](std::mt19937_64& rng) {
                      std::uniform_real_distribution<double> u(0.0, 1.0);
                      const auto p = [&] { return Vector3d(u(rng), u(rng), u(rng)); };
                      const TrianglePoints s = tri(p);
                      const Vector3d on = s.a + u(rng) * (s.b - s.a);
                      return std::make_pair(s, TrianglePoints{on, p(), p()});
                    }});
  return scenes;
}

/// Formats a pair with hexadecimal floats so that a failure can be reproduced exactly.
inline std::string Describe(const TrianglePoints& s, const TrianglePoints& t) {
  std::string out;
  char buf[96];
  for (const Eigen::Vector3d* p : {&s.a, &s.b, &s.c, &t.a, &t.b, &t.c}) {
    std::snprintf(buf, sizeof(buf), "(%a, %a, %a) ", p->x(), p->y(), p->z());
    out += buf;
  }
  return out;
}

}  // namespace far::reference
