#include "result_json.h"

namespace far::cli {

using nlohmann::json;

json StatsJson(const StepStats& stats) {
  json stages = json::object();
  for (const auto& stage : stats.stages) stages[stage.name] = stage.ms;
  return {{"method", stats.method},
          {"method_reason", stats.method_reason},
          {"total_ms", stats.total_ms},
          {"stages_ms", stages},
          {"primitives_rendered", stats.primitives_rendered},
          {"draws", stats.draws},
          {"queries", stats.queries},
          {"bytes_uploaded", stats.bytes_uploaded},
          {"object_pairs", stats.object_pairs},
          {"pairs_considered", stats.pairs_considered},
          {"pairs_tested", stats.pairs_tested},
          {"object_radius", stats.object_radius},
          {"primitive_radius", stats.primitive_radius}};
}

json ResultJson(const StepResult& result) {
  json contacts = json::array(), distance_pairs = json::array(), pcs_primitives = json::object();
  for (const auto& c : result.contacts)
    contacts.push_back({c.object_a, c.triangle_a, c.object_b, c.triangle_b});
  for (const auto& d : result.distance_pairs) {
    distance_pairs.push_back(
        {d.pair.object_a, d.pair.triangle_a, d.pair.object_b, d.pair.triangle_b, d.distance});
  }
  for (const auto& [id, triangles] : result.pcs_primitives)
    pcs_primitives[std::to_string(id)] = triangles;
  json pairs = json::array();
  for (const auto& p : result.object_pairs) pairs.push_back({p.object_a, p.object_b});
  return {{"contacts", contacts},
          {"distance_pairs", distance_pairs},
          {"pcs_objects", result.pcs_objects},
          {"pcs_primitives", pcs_primitives},
          {"object_pairs", pairs},
          {"stats", StatsJson(result.stats)}};
}

}  // namespace far::cli
