#include "arrays.h"

#include <cstdint>
#include <cstring>
#include <string>

#include "errors.h"

namespace py = pybind11;

namespace far::python {
namespace {

std::string Describe(const py::array& a) {
  std::string shape = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(a.shape(i));
  if (a.ndim() == 1) shape += ",";
  return std::string(py::str(a.dtype())) + " array of shape " + shape + ")";
}

// The checks both arguments share: an ndarray of dtype T, shape (N, 3), C-contiguous rows of
// three packed elements, aligned for T.
template <typename T>
py::array CheckRows3(const py::handle& handle, const char* argument, const char* dtype_name) {
  const std::string expected =
      std::string("expected a C-contiguous numpy ") + dtype_name + " array of shape (N, 3)";
  if (!py::isinstance<py::array>(handle)) {
    ThrowArgument(argument, expected + ", got " +
                                std::string(py::str(py::type::handle_of(handle).attr("__name__"))) +
                                " (convert with numpy.ascontiguousarray(x, dtype=numpy." +
                                dtype_name + "))");
  }
  py::array a = py::reinterpret_borrow<py::array>(handle);
  if (!a.dtype().is(py::dtype::of<T>()) && !a.dtype().equal(py::dtype::of<T>())) {
    ThrowArgument(argument, expected + ", got a " + Describe(a) +
                                " (never converted: numpy.ascontiguousarray(x, dtype=numpy." +
                                dtype_name + ") makes the copy explicit)");
  }
  if (a.ndim() != 2 || a.shape(1) != 3)
    ThrowArgument(argument, expected + ", got a " + Describe(a));
  if (a.shape(0) == 0) return a;  // nothing is read: any strides and address do
  const auto elem = static_cast<py::ssize_t>(sizeof(T));
  const bool rows_packed = a.shape(0) <= 1 || a.strides(0) == 3 * elem;
  if (!rows_packed || a.strides(1) != elem ||
      reinterpret_cast<std::uintptr_t>(a.data()) % alignof(T) != 0) {
    ThrowArgument(argument, expected + ", got a non-contiguous " + Describe(a) +
                                " (a view with strides; numpy.ascontiguousarray(x) copies it)");
  }
  return a;
}

}  // namespace

std::span<const Eigen::Vector3d> Vector3Span(const py::handle& handle, const char* argument) {
  static_assert(
      sizeof(Eigen::Vector3d) == 3 * sizeof(double) && alignof(Eigen::Vector3d) == alignof(double),
      "Vector3d is three packed doubles");
  py::array a = CheckRows3<double>(handle, argument, "float64");
  if (a.shape(0) == 0) return {};
  return {static_cast<const Eigen::Vector3d*>(a.data()), static_cast<size_t>(a.shape(0))};
}

std::vector<TriangleIndices> Triangles(const py::handle& handle, const char* argument) {
  py::array a = CheckRows3<uint32_t>(handle, argument, "uint32");
  std::vector<TriangleIndices> triangles(static_cast<size_t>(a.shape(0)));
  if (!triangles.empty())
    std::memcpy(triangles.data(), a.data(), triangles.size() * sizeof(TriangleIndices));
  return triangles;
}

}  // namespace far::python
