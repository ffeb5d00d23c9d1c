#include "pose.h"

#include <array>

#include "errors.h"
#include <pybind11/numpy.h>

namespace py = pybind11;

namespace far::python {
namespace {

template <size_t N>
std::array<double, N> Numbers(const py::handle& value, const char* argument) {
  const std::string expected = "expected " + std::to_string(N) + " numbers";
  if (py::isinstance<py::array>(value)) {
    py::array a = py::reinterpret_borrow<py::array>(value);
    if (!a.dtype().equal(py::dtype::of<double>()))
      ThrowArgument(argument, expected + " as float64, got a " + std::string(py::str(a.dtype())) +
                                  " array (never converted)");
    if (a.ndim() != 1 || a.shape(0) != static_cast<py::ssize_t>(N))
      ThrowArgument(argument, expected + ", got an array of " + std::to_string(a.size()) +
                                  " elements in " + std::to_string(a.ndim()) + " dimensions");
  } else if (!py::isinstance<py::sequence>(value) || py::isinstance<py::str>(value)) {
    ThrowArgument(argument, expected + ", got " +
                                std::string(py::str(py::type::handle_of(value).attr("__name__"))));
  }
  py::sequence sequence = py::reinterpret_borrow<py::sequence>(value);
  if (sequence.size() != N)
    ThrowArgument(argument, expected + ", got " + std::to_string(sequence.size()));
  std::array<double, N> out{};
  for (size_t i = 0; i < N; ++i) {
    py::object item = sequence[i];
    // bool is an int in Python; a pose made of True and False is a bug, not a number.
    if (py::isinstance<py::bool_>(item) ||
        !(py::isinstance<py::float_>(item) || py::isinstance<py::int_>(item) ||
          py::hasattr(item, "__float__")))
      ThrowArgument(argument, expected + "; element " + std::to_string(i) + " is " +
                                  std::string(py::str(py::repr(item))));
    out[i] = item.cast<double>();
  }
  return out;
}

}  // namespace

Pose ToPose(const py::handle& translation, const py::handle& rotation_wxyz) {
  const auto t = Numbers<3>(translation, "translation");
  const auto q = Numbers<4>(rotation_wxyz, "rotation_wxyz");
  Pose pose;
  pose.translation = {t[0], t[1], t[2]};
  pose.rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
  return pose;
}

Motion ToMotion(const std::string& motion) {
  if (auto m = ParseMotion(motion)) return *m;
  ThrowArgument("motion", "unknown '" + motion + "'; the motions are: static, rigid, deformable");
}

}  // namespace far::python
