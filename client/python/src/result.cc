#include "result.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

namespace py = pybind11;

namespace far::python {
namespace {

template <typename T>
py::array_t<T> Array(std::initializer_list<py::ssize_t> shape) {
  return py::array_t<T>(std::vector<py::ssize_t>(shape));
}

// Rows of 3 doubles: out[i] = get(items[i]).
template <typename Items, typename Get>
py::array_t<double> Points(const Items& items, Get get) {
  auto out = Array<double>({static_cast<py::ssize_t>(items.size()), 3});
  double* p = out.mutable_data();
  for (const auto& item : items) {
    const Eigen::Vector3d& v = get(item);
    *p++ = v.x(), *p++ = v.y(), *p++ = v.z();
  }
  return out;
}

// A class of far._result, looked up once (a step builds one StepResult: the import and the
// attribute lookups were a measurable part of the binding's time per step). Deliberately
// leaked: a py::object destroyed after the interpreter would crash at exit.
py::handle ResultClass(const char* name) {
  static py::module_* module = new py::module_(py::module_::import("far._result"));
  return py::object(module->attr(name)).release();
}

py::handle StepResultClass() {
  static const py::handle cls = ResultClass("StepResult");
  return cls;
}

py::handle PenetrationsClass() {
  static const py::handle cls = ResultClass("Penetrations");
  return cls;
}

template <typename Pair>
void PutPair(int64_t*& p, const Pair& c) {
  *p++ = c.object_a, *p++ = c.triangle_a, *p++ = c.object_b, *p++ = c.triangle_b;
}

py::object Penetrations(const std::vector<Penetration>& penetrations) {
  const auto n = static_cast<py::ssize_t>(penetrations.size());
  auto objects = Array<int64_t>({n, 2});
  auto closed = Array<bool>({n});
  auto depth = Array<double>({n});
  int64_t* o = objects.mutable_data();
  for (py::ssize_t i = 0; i < n; ++i) {
    const Penetration& p = penetrations[static_cast<size_t>(i)];
    *o++ = p.object_a, *o++ = p.object_b;
    closed.mutable_data()[i] = p.closed;
    depth.mutable_data()[i] = p.depth;
  }
  return PenetrationsClass()(
      py::arg("objects") = objects, py::arg("closed") = closed, py::arg("depth") = depth,
      py::arg("direction") = Points(penetrations, [](const auto& p) { return p.direction; }),
      py::arg("point_a") = Points(penetrations, [](const auto& p) { return p.point_a; }),
      py::arg("point_b") = Points(penetrations, [](const auto& p) { return p.point_b; }));
}

}  // namespace

py::dict StatsDict(const StepStats& stats) {
  py::dict stages;
  for (const StageStats& stage : stats.stages) stages[py::str(ToString(stage.stage))] = stage.ms;
  py::list levels;
  for (const LevelCertificate& level : stats.certificate.levels) {
    levels.append(py::dict(
        py::arg("level") = level.level, py::arg("views") = level.views,
        py::arg("resolution") = level.resolution, py::arg("offset_radius") = level.offset_radius,
        py::arg("pixel_size") = level.pixel_size, py::arg("depth_step") = level.depth_step,
        py::arg("rounding") = level.rounding, py::arg("world_min") = level.world_min,
        py::arg("world_max") = level.world_max));
  }
  py::dict stats_dict(
      py::arg("method") = stats.method, py::arg("method_reason") = stats.method_reason,
      py::arg("total_ms") = stats.total_ms, py::arg("stages_ms") = stages,
      py::arg("primitives_rendered") = stats.primitives_rendered, py::arg("draws") = stats.draws,
      py::arg("queries") = stats.queries, py::arg("bytes_uploaded") = stats.bytes_uploaded,
      py::arg("object_pairs") = stats.object_pairs,
      py::arg("pairs_considered") = stats.pairs_considered,
      py::arg("pairs_tested") = stats.pairs_tested, py::arg("object_radius") = stats.object_radius,
      py::arg("primitive_radius") = stats.primitive_radius,
      py::arg("certificate") =
          py::dict(py::arg("guaranteed") = stats.certificate.guaranteed,
                   py::arg("basis") = stats.certificate.basis, py::arg("levels") = levels));
  // In process only (far.Pipeline): the daemon does not send these (step_result.h).
  stats_dict["gl_prepare_ms"] = stats.gl_prepare_ms;
  stats_dict["gl_passes_ms"] = stats.gl_passes_ms;
  stats_dict["gl_gpu_ms"] = stats.gl_gpu_ms;
  return stats_dict;
}

py::object ToPython(const StepResult& result) {
  const auto n = static_cast<py::ssize_t>(result.contacts.size());
  const auto m = static_cast<py::ssize_t>(result.distance_pairs.size());
  auto contacts = Array<int64_t>({n, 4});
  int64_t* c = contacts.mutable_data();
  for (const ContactPair& pair : result.contacts) PutPair(c, pair);

  auto distance_pairs = Array<int64_t>({m, 4});
  auto distances = Array<double>({m});
  int64_t* d = distance_pairs.mutable_data();
  for (py::ssize_t i = 0; i < m; ++i) {
    PutPair(d, result.distance_pairs[static_cast<size_t>(i)].pair);
    distances.mutable_data()[i] = result.distance_pairs[static_cast<size_t>(i)].distance;
  }

  auto pcs_objects = Array<int64_t>({static_cast<py::ssize_t>(result.pcs_objects.size())});
  for (size_t i = 0; i < result.pcs_objects.size(); ++i)
    pcs_objects.mutable_data()[i] = result.pcs_objects[i];
  auto object_pairs = Array<int64_t>({static_cast<py::ssize_t>(result.object_pairs.size()), 2});
  int64_t* op = object_pairs.mutable_data();
  for (const ObjectPair& pair : result.object_pairs) *op++ = pair.object_a, *op++ = pair.object_b;
  py::dict pcs_primitives;
  for (const auto& [id, triangles] : result.pcs_primitives) {
    auto t = Array<int64_t>({static_cast<py::ssize_t>(triangles.size())});
    for (size_t i = 0; i < triangles.size(); ++i) t.mutable_data()[i] = triangles[i];
    pcs_primitives[py::int_(id)] = t;
  }

  // Contact geometry: counts, then every contact's points one after the other.
  const auto& geometry = result.contact_geometry;
  auto counts = Array<int64_t>({static_cast<py::ssize_t>(geometry.size())});
  auto coplanar = Array<bool>({static_cast<py::ssize_t>(geometry.size())});
  py::ssize_t total_points = 0;
  for (size_t i = 0; i < geometry.size(); ++i) {
    counts.mutable_data()[i] = geometry[i].num_points;
    coplanar.mutable_data()[i] = geometry[i].coplanar;
    total_points += geometry[i].num_points;
  }
  auto points = Array<double>({total_points, 3});
  double* p = points.mutable_data();
  for (const ContactGeometry& g : geometry) {
    for (int k = 0; k < g.num_points; ++k) {
      *p++ = g.points[static_cast<size_t>(k)].x(), *p++ = g.points[static_cast<size_t>(k)].y(),
      *p++ = g.points[static_cast<size_t>(k)].z();
    }
  }

  return StepResultClass()(
      py::arg("contacts") = contacts, py::arg("distance_pairs") = distance_pairs,
      py::arg("distances") = distances, py::arg("pcs_objects") = pcs_objects,
      py::arg("object_pairs") = object_pairs, py::arg("pcs_primitives") = pcs_primitives,
      py::arg("contact_point_counts") = counts, py::arg("contact_points") = points,
      py::arg("normals_a") = Points(geometry, [](const auto& g) { return g.normal_a; }),
      py::arg("normals_b") = Points(geometry, [](const auto& g) { return g.normal_b; }),
      py::arg("coplanar") = coplanar,
      py::arg("closest_points_a") =
          Points(result.closest_points, [](const auto& c) { return c.point_a; }),
      py::arg("closest_points_b") =
          Points(result.closest_points, [](const auto& c) { return c.point_b; }),
      py::arg("penetrations") = Penetrations(result.penetrations),
      py::arg("stats") = StatsDict(result.stats));
}

}  // namespace far::python
