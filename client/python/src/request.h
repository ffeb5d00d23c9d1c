#pragma once
// far.Client.step's and far.Pipeline.step's keyword arguments -> far::StepRequest: the options
// of far-client collide (--method, --mechanism, --resolution, --depth-format, --subobject-size,
// --distance, --output, --geometry), by the same names and with the same defaults.
#include <optional>
#include <string>

#include <pybind11/pybind11.h>

#include "far/model/step_request.h"

namespace far::python {

/// Checks the names and CheckStepRequest; errors (far.InvalidArgumentError) start with the
/// argument ("method: unknown 'x'; ...", "resolution: 5 is outside [8, 8192]").
/// output None: "contacts", or "distance" when a distance is given (as far-client).
StepRequest ToStepRequest(const std::string& method, const std::string& mechanism, int resolution,
                          const std::string& depth_format, int subobject_size,
                          std::optional<double> distance, std::optional<std::string> output,
                          bool geometry);

/// Adds the step's keyword arguments (after `*`) to a pybind11 method definition.
#define FAR_PYTHON_STEP_ARGS                                                             \
  pybind11::kw_only(),                                                                   \
      pybind11::arg("method") = "auto", pybind11::arg("mechanism") = "id-buffer",        \
      pybind11::arg("resolution") = 1024, pybind11::arg("depth_format") = "depth24",     \
      pybind11::arg("subobject_size") = 1, pybind11::arg("distance") = pybind11::none(), \
      pybind11::arg("output") = pybind11::none(), pybind11::arg("geometry") = false

}  // namespace far::python
