#pragma once
// far::StepResult -> far.StepResult (far/_result.py): NumPy arrays that own their memory, and
// the stats as a dict (the fields of far-client's JSON "stats", plus the profiling counters).
#include <pybind11/pybind11.h>

#include "far/model/step_result.h"

namespace far::python {

pybind11::object ToPython(const StepResult& result);
pybind11::dict StatsDict(const StepStats& stats);

}  // namespace far::python
