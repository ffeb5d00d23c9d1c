#pragma once
// A step's result as JSON, as collide and play --json print it.
#include <nlohmann/json.hpp>

#include "far/model/step_result.h"

namespace far::cli {

nlohmann::json StatsJson(const StepStats& stats);
nlohmann::json ResultJson(const StepResult& result);

}  // namespace far::cli
