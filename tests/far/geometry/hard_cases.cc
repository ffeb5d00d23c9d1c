#include "hard_cases.h"

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "exact_reference.h"

namespace far::reference {
namespace {

using Eigen::Vector3d;

// A base configuration in a small frame with dyadic coordinates, so that the exact transforms
// below keep it exact.
struct Base {
  std::string name;
  std::string category;
  TrianglePoints s, t;
  std::optional<bool> intended;
  // Optional separating axis: s lies in {x[axis] <= c} and t in {x[axis] >= c} when away_sign
  // is +1 (mirrored for -1), so moving t along away_sign * e_axis separates them.
  int away_axis = -1;
  int away_sign = 0;
};

Vector3d V(double x, double y, double z) { return Vector3d(x, y, z); }

std::vector<Base> MakeBases() {
  std::vector<Base> b;
  const TrianglePoints s0 = Tri(V(0, 0, 0), V(4, 0, 0), V(0, 4, 0));  // right triangle in z = 0
  const double h = std::ldexp(1.0, -27);  // sliver height: aspect ratio 1 / h = 1.3e8
  const double up = std::nextafter(2.0, 3.0);
  const double down = std::nextafter(2.0, 1.0);

  // --- Coplanar (z = 0) -------------------------------------------------------------------
  b.push_back({"copl_overlap", "coplanar", s0, Tri(V(1, 1, 0), V(5, 1, 0), V(1, 5, 0)), true});
  b.push_back({"copl_contained", "coplanar", s0, Tri(V(1, 1, 0), V(2, 1, 0), V(1, 2, 0)), true});
  b.push_back({"copl_star", "coplanar", Tri(V(0, 0, 0), V(4, 0, 0), V(2, 3, 0)),
               Tri(V(0, 2, 0), V(4, 2, 0), V(2, -1, 0)), true});
  b.push_back(
      {"copl_vertex_touch", "coplanar", s0, Tri(V(4, 0, 0), V(6, -1, 0), V(6, 1, 0)), true, 0, +1});
  b.push_back({"copl_vertex_on_edge", "coplanar", s0, Tri(V(2, 0, 0), V(3, -2, 0), V(1, -2, 0)),
               true, 1, -1});
  b.push_back(
      {"copl_edge_overlap", "coplanar", s0, Tri(V(2, 0, 0), V(6, 0, 0), V(4, -2, 0)), true, 1, -1});
  b.push_back({"copl_shared_edge", "coplanar", s0, Tri(V(4, 0, 0), V(0, 4, 0), V(4, 4, 0)), true});
  b.push_back({"copl_collinear_edges_touch", "coplanar", s0,
               Tri(V(4, 0, 0), V(8, 0, 0), V(6, -2, 0)), true, 0, +1});
  b.push_back({"copl_hypotenuse_ulp_outside", "coplanar", s0,
               Tri(V(2, up, 0), V(4, 4, 0), V(2, 5, 0)), false});
  b.push_back({"copl_hypotenuse_ulp_inside", "coplanar", s0,
               Tri(V(2, down, 0), V(4, 4, 0), V(2, 5, 0)), true});
  b.push_back(
      {"copl_hypotenuse_touch", "coplanar", s0, Tri(V(2, 2, 0), V(4, 4, 0), V(2, 5, 0)), true});
  b.push_back({"copl_parallel_gap", "coplanar", s0,
               Tri(V(0, -std::ldexp(1.0, -30), 0), V(4, -std::ldexp(1.0, -30), 0), V(2, -3, 0)),
               false});
  b.push_back({"copl_stacked_ulp", "coplanar", Tri(V(0, 0, 1), V(4, 0, 1), V(0, 4, 1)),
               Tri(V(1, 1, std::nextafter(1.0, 2.0)), V(5, 1, std::nextafter(1.0, 2.0)),
                   V(1, 5, std::nextafter(1.0, 2.0))),
               false});
  b.push_back({"copl_stacked_touch", "coplanar", Tri(V(0, 0, 1), V(4, 0, 1), V(0, 4, 1)),
               Tri(V(1, 1, 1), V(5, 1, 1), V(1, 5, 1)), true, 2, +1});

  // --- Non-coplanar contacts --------------------------------------------------------------
  b.push_back({"pierce", "crossing", s0, Tri(V(1, 1, -1), V(1, 1, 1), V(2, 1, 0)), true});
  b.push_back(
      {"crossing_generic", "crossing", s0, Tri(V(1, 0.5, -1), V(3, 1, 1), V(0.5, 3, 2)), true});
  b.push_back({"shared_vertex_above", "shared", s0, Tri(V(0, 0, 0), V(-1, 1, 3), V(1, -2, 2)), true,
               2, +1});
  b.push_back({"shared_vertex_through", "shared", s0, Tri(V(0, 0, 0), V(-1, -1, 2), V(-1, -1, -2)),
               true, 0, -1});
  b.push_back(
      {"shared_edge_hinge", "shared", s0, Tri(V(0, 0, 0), V(4, 0, 0), V(2, 0, 3)), true, 1, -1});
  b.push_back({"shared_edge_fold", "shared", s0, Tri(V(4, 0, 0), V(0, 4, 0), V(3, 3, 2)), true});
  b.push_back(
      {"vertex_on_face", "vertex_face", s0, Tri(V(1, 1, 0), V(0, 0, 2), V(3, 0, 2)), true, 2, +1});
  b.push_back(
      {"vertex_on_edge", "vertex_face", s0, Tri(V(2, 0, 0), V(2, -1, 2), V(3, 1, 2)), true, 2, +1});
  b.push_back({"vertex_on_tilted_face", "vertex_face", Tri(V(0, 0, 0), V(4, 0, 4), V(0, 4, 4)),
               Tri(V(1, 1, 2), V(1, 1, 5), V(2, 0, 5)), true});
  b.push_back({"edge_edge_cross", "edge_edge", Tri(V(0, 0, 0), V(4, 0, 0), V(2, -2, -2)),
               Tri(V(2, -1, 0), V(2, 1, 0), V(2, 0, 2)), true, 2, +1});
  b.push_back({"edge_edge_skew_close", "edge_edge", Tri(V(0, 0, 0), V(4, 0, 0), V(2, -2, -2)),
               Tri(V(2, -1, std::ldexp(1.0, -40)), V(2, 1, std::ldexp(1.0, -40)), V(2, 0, 2)),
               false});
  b.push_back({"parallel_planes", "crossing", s0, Tri(V(0, 0, 1), V(4, 0, 1), V(0, 4, 1)), false});

  // --- Slivers (aspect ratio ~1.3e8) ------------------------------------------------------
  const TrianglePoints cap = Tri(V(0, 0, 0), V(1, 0, 0), V(0.5, h, 0));
  const TrianglePoints needle = Tri(V(0, 0, 0), V(1, 0, 0), V(1, h, 0));
  b.push_back({"sliver_pierced", "sliver", cap,
               Tri(V(0.5, h / 2, -1), V(0.5, h / 2, 1), V(0.75, h / 2, 0)), true});
  b.push_back({"sliver_apex_touch", "sliver", cap, Tri(V(0.5, h, -1), V(0.5, h, 1), V(0.25, h, 0)),
               true, 1, +1});
  b.push_back({"sliver_cross_sliver", "sliver", cap,
               Tri(V(0.5, -0.5, -h), V(0.5, 0.5, -h), V(0.5, 0, h)), true});
  const double x0 = std::ldexp(1.0, -20);
  b.push_back({"needle_tip_inside", "sliver", needle,
               Tri(V(x0, h * x0 / 2, -1), V(x0, h * x0 / 2, 1), V(x0 / 2, h * x0 / 2, 0)), true});
  b.push_back({"needle_tip_touch", "sliver", needle,
               Tri(V(x0, h * x0, -1), V(x0, h * x0, 1), V(x0 / 2, h * x0, 0)), true});
  b.push_back({"needle_tip_ulp_miss", "sliver", needle,
               Tri(V(x0, std::nextafter(h * x0, 1.0), -1), V(x0, std::nextafter(h * x0, 1.0), 1),
                   V(x0 / 2, std::nextafter(h * x0, 1.0), 0)),
               false});
  b.push_back({"sliver_coplanar_overlap", "sliver", cap,
               Tri(V(0, h / 2, 0), V(1, h / 2, 0), V(0.5, -h / 2, 0)), true});
  b.push_back({"sliver_coplanar_base_touch", "sliver", cap,
               Tri(V(0.25, 0, 0), V(0.75, 0, 0), V(0.5, -h, 0)), true, 1, -1});
  b.push_back({"sliver_stacked", "sliver", cap,
               Tri(V(0, 0, h), V(1, 0, h / 2), V(0.5, h, std::ldexp(1.0, -60))), false});
  b.push_back(
      {"sliver_stacked_touch", "sliver", cap, Tri(V(0, 0, h), V(1, 0, h / 2), V(0.5, h, 0)), true});

  // --- Collinear (degenerate) triangles ---------------------------------------------------
  b.push_back(
      {"collinear_pierce", "collinear", s0, Tri(V(1, 1, -1), V(1, 1, 0.5), V(1, 1, 2)), true});
  b.push_back({"collinear_touch_vertex", "collinear", s0, Tri(V(0, 0, 0), V(0, 0, 1), V(0, 0, 2)),
               true, 2, +1});
  b.push_back(
      {"collinear_above", "collinear", s0, Tri(V(1, 1, 0.5), V(1, 1, 1), V(1, 1, 2)), false});
  b.push_back({"collinear_in_plane_cross", "collinear", s0,
               Tri(V(-1, 1, 0), V(1, 1, 0), V(3, 1, 0)), true});
  b.push_back({"collinear_in_plane_touch_vertex", "collinear", s0,
               Tri(V(4, 0, 0), V(5, 0, 0), V(6, 0, 0)), true, 0, +1});
  b.push_back({"collinear_in_plane_touch_edge", "collinear", s0,
               Tri(V(-2, 2, 0), V(-1, 2, 0), V(0, 2, 0)), true, 0, -1});
  b.push_back({"collinear_repeated_point", "collinear", s0,
               Tri(V(1, 1, -1), V(1, 1, -1), V(1, 1, 2)), true});
  const TrianglePoints diag = Tri(V(0, 0, 0), V(1, 1, 0), V(2, 2, 0));
  b.push_back({"collinear_pair_cross", "collinear", diag,
               Tri(V(0, 2, 0), V(2, 0, 0), V(0.5, 1.5, 0)), true});
  b.push_back(
      {"collinear_pair_skew", "collinear", diag, Tri(V(0, 2, 1), V(2, 0, 1), V(1, 1, 1)), false});
  const TrianglePoints xline = Tri(V(0, 0, 0), V(1, 0, 0), V(2, 0, 0));
  b.push_back({"collinear_same_line_overlap", "collinear", xline,
               Tri(V(1.5, 0, 0), V(3, 0, 0), V(4, 0, 0)), true});
  b.push_back({"collinear_same_line_touch", "collinear", xline,
               Tri(V(2, 0, 0), V(3, 0, 0), V(4, 0, 0)), true, 0, +1});
  b.push_back({"collinear_parallel_lines", "collinear", xline,
               Tri(V(0, 0, std::ldexp(1.0, -30)), V(1, 0, std::ldexp(1.0, -30)),
                   V(2, 0, std::ldexp(1.0, -30))),
               false});
  b.push_back({"collinear_t_junction", "collinear", xline,
               Tri(V(1, -1, 0), V(1, -2, 0), V(1, 0, 0)), true, 1, -1});

  // --- Point triangles --------------------------------------------------------------------
  const auto point = [](double x, double y, double z) {
    return Tri(V(x, y, z), V(x, y, z), V(x, y, z));
  };
  b.push_back({"point_in_face", "point", s0, point(1, 1, 0), true, 2, +1});
  b.push_back({"point_on_edge", "point", s0, point(2, 0, 0), true, 1, -1});
  b.push_back({"point_at_vertex", "point", s0, point(4, 0, 0), true, 0, +1});
  b.push_back({"point_above", "point", s0, point(1, 1, 1), false});
  b.push_back({"point_on_tilted_face", "point", Tri(V(0, 0, 0), V(4, 0, 4), V(0, 4, 4)),
               point(1, 1, 2), true});
  b.push_back({"point_point_equal", "point", point(1, 2, 3), point(1, 2, 3), true, 0, +1});
  b.push_back({"point_on_collinear", "point", Tri(V(0, 0, 0), V(2, 2, 2), V(1, 1, 1)),
               point(0.5, 0.5, 0.5), true});
  b.push_back({"point_at_collinear_end", "point", xline, point(2, 0, 0), true, 0, +1});
  return b;
}

// An exact affine map: permute and flip axes, optionally shear (tilting the plane z = 0 to
// z = x/2 + y/4), then scale by a power of two and translate by an integer vector.
struct Transform {
  std::string name;
  std::array<int, 3> perm = {0, 1, 2};
  std::array<int, 3> sign = {1, 1, 1};
  bool shear = false;
  double scale = 1.0;
  Vector3d offset = Vector3d::Zero();

  Vector3d Apply(const Vector3d& p) const {
    Vector3d q(sign[0] * p[perm[0]], sign[1] * p[perm[1]], sign[2] * p[perm[2]]);
    if (shear) q.z() += q.x() / 2 + q.y() / 4;
    return offset + scale * q;
  }
  TrianglePoints Apply(const TrianglePoints& t) const {
    return TrianglePoints{Apply(t.a), Apply(t.b), Apply(t.c)};
  }
  // Returns true iff Apply(p) rounded nothing: compares with the map in rationals.
  bool IsExactFor(const Vector3d& p) const {
    std::array<mpq_class, 3> q;
    for (int k = 0; k < 3; ++k) q[k] = sign[k] * mpq_class(p[perm[k]]);
    if (shear) q[2] += q[0] / 2 + q[1] / 4;
    const Vector3d rounded = Apply(p);
    for (int k = 0; k < 3; ++k) {
      if (mpq_class(rounded[k]) != mpq_class(offset[k]) + mpq_class(scale) * q[k]) return false;
    }
    return true;
  }
  bool IsExactFor(const TrianglePoints& t) const {
    return IsExactFor(t.a) && IsExactFor(t.b) && IsExactFor(t.c);
  }
};

std::vector<Transform> MakeTransforms() {
  const double feature = std::ldexp(1.0, -10);  // about 1e-3
  std::vector<Transform> transforms;
  transforms.push_back({"id"});
  transforms.push_back({"perm", {2, 0, 1}, {-1, 1, -1}});
  transforms.push_back({"tilt", {0, 1, 2}, {1, 1, 1}, true});
  transforms.push_back({"1e5", {1, 2, 0}, {1, -1, 1}, false, feature, Vector3d(1e5, 1e5, -1e5)});
  transforms.push_back({"1e6", {0, 1, 2}, {1, 1, 1}, false, feature, Vector3d(1e6, -1e6, 1e6)});
  transforms.push_back({"tilt1e6", {0, 1, 2}, {1, 1, 1}, true, feature, Vector3d(-1e6, 1e6, 1e6)});
  return transforms;
}

// Moves every vertex of t along `axis` by `sign`: by one ulp (ulps = true) or by delta. A zero
// coordinate moves by one ulp of `scale` instead, so that no subnormal number is made (the
// predicates are exact only for normal numbers, see far/internal/predicates.h).
TrianglePoints Nudge(TrianglePoints t, int axis, int sign, bool ulps, double delta, double scale) {
  const double toward = sign > 0 ? HUGE_VAL : -HUGE_VAL;
  for (Vector3d* p : {&t.a, &t.b, &t.c}) {
    double& x = (*p)[axis];
    if (!ulps) {
      x += sign * delta;
    } else if (x == 0.0) {
      x = sign * (std::nextafter(scale, HUGE_VAL) - scale);
    } else {
      x = std::nextafter(x, toward);
    }
  }
  return t;
}

double MaxAbs(const TrianglePoints& s, const TrianglePoints& t) {
  double m = 0;
  for (const Vector3d* p : {&s.a, &s.b, &s.c, &t.a, &t.b, &t.c})
    m = std::max(m, p->cwiseAbs().maxCoeff());
  return m;
}

}  // namespace

std::vector<HardCase> MakeHardCases() {
  std::vector<HardCase> cases;
  const auto add = [&cases](std::string name, const std::string& category, const TrianglePoints& s,
                            const TrianglePoints& t, std::optional<bool> intended) {
    HardCase c;
    c.name = std::move(name);
    c.category = category;
    c.s = s;
    c.t = t;
    c.intersect = ExactTrianglesIntersect(s, t);
    c.intended = intended;
    cases.push_back(std::move(c));
  };
  for (const Base& base : MakeBases()) {
    for (const Transform& tf : MakeTransforms()) {
      const TrianglePoints s = tf.Apply(base.s);
      const TrianglePoints t = tf.Apply(base.t);
      // Where the transform had to round (slivers far from the origin), the construction's
      // intent no longer holds; the reference still gives the exact answer for what we built.
      const bool exact = tf.IsExactFor(base.s) && tf.IsExactFor(base.t);
      const std::string name = base.name + "@" + tf.name + (exact ? "" : "~");
      add(name, base.category, s, t, exact ? base.intended : std::nullopt);
      if (base.away_axis < 0 || tf.shear) continue;
      // The separating axis after the transform: axis k with perm[k] == away_axis.
      int axis = 0;
      while (tf.perm[axis] != base.away_axis) ++axis;
      const int sign = base.away_sign * tf.sign[axis];
      const double scale = std::max(1.0, MaxAbs(s, t));
      const double delta = 1e-9 * scale;
      add(name + "+ulp", base.category, s, Nudge(t, axis, sign, true, 0, scale), false);
      add(name + "+1e-9rel", base.category, s, Nudge(t, axis, sign, false, delta, scale), false);
      add(name + "-ulp", base.category, s, Nudge(t, axis, -sign, true, 0, scale), std::nullopt);
      add(name + "-1e-9rel", base.category, s, Nudge(t, axis, -sign, false, delta, scale),
          std::nullopt);
    }
  }
  return cases;
}

std::vector<std::pair<TrianglePoints, TrianglePoints>> Relabelings(const TrianglePoints& s,
                                                                   const TrianglePoints& t) {
  static constexpr std::array<std::array<int, 3>, 6> kOrders = {
      {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}}};
  const std::array<Vector3d, 3> sv = {s.a, s.b, s.c};
  const std::array<Vector3d, 3> tv = {t.a, t.b, t.c};
  std::vector<std::pair<TrianglePoints, TrianglePoints>> out;
  out.reserve(72);
  for (const auto& os : kOrders) {
    for (const auto& ot : kOrders) {
      const TrianglePoints s2{sv[os[0]], sv[os[1]], sv[os[2]]};
      const TrianglePoints t2{tv[ot[0]], tv[ot[1]], tv[ot[2]]};
      out.emplace_back(s2, t2);
      out.emplace_back(t2, s2);
    }
  }
  return out;
}

}  // namespace far::reference
