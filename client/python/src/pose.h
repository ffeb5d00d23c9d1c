#pragma once
// Poses and motions from Python arguments: translation (3 numbers) and rotation_wxyz (4, a unit
// quaternion w first, as in scene files). Small, so taken by value from any sequence of real
// numbers; a NumPy array must still be float64 (a wrong dtype is refused, never converted).
#include <string>

#include <pybind11/pybind11.h>

#include "far/model/pose.h"

namespace far::python {

Pose ToPose(const pybind11::handle& translation, const pybind11::handle& rotation_wxyz);
/// "static", "rigid" or "deformable".
Motion ToMotion(const std::string& motion);

}  // namespace far::python
