#pragma once
// A step's result as JSON, as collide and play --json print it.
#include <string>

#include <nlohmann/json.hpp>

#include "far/model/step_result.h"

namespace far::cli {

nlohmann::json CertificateJson(const Certificate& certificate);
/// The certificate in lines: its basis, then one line per GPU culling level (where the
/// distance D is asked for, r covers D/2 as well).
std::string CertificateText(const Certificate& certificate);
nlohmann::json StatsJson(const StepStats& stats);
/// With `geometry` (the step asked for it): also "contact_geometry" (per contact: points,
/// normal_a, normal_b, coplanar), "closest_points" (per distance pair: point_a, point_b) and
/// "penetrations" (per object pair in contact: objects, closed, and when closed depth,
/// direction, point_a, point_b).
nlohmann::json ResultJson(const StepResult& result, bool geometry = false);

}  // namespace far::cli
