#pragma once
// NumPy arguments, checked and never converted: an array of the wrong dtype, shape or layout is
// far.InvalidArgumentError naming the argument, not a silent copy or reinterpretation
// (docs/python.md, "Arrays").
#include <span>
#include <vector>

#include <Eigen/Core>
#include <pybind11/numpy.h>

#include "far/model/mesh.h"

namespace far::python {

/// A float64 C-contiguous aligned (N, 3) ndarray as N Eigen::Vector3d over the array's own
/// memory (no copy): Vector3d is three packed doubles, exactly a row of that array. The caller
/// keeps `array` alive while the span is used.
std::span<const Eigen::Vector3d> Vector3Span(const pybind11::handle& array, const char* argument);
/// A uint32 C-contiguous (M, 3) ndarray as triangles (copied: a Mesh owns its triangles).
std::vector<TriangleIndices> Triangles(const pybind11::handle& array, const char* argument);

}  // namespace far::python
