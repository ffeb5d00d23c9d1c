#include "result_json.h"

#include <cstdio>

namespace far::cli {

using nlohmann::json;

json CertificateJson(const Certificate& certificate) {
  json levels = json::array();
  for (const LevelCertificate& level : certificate.levels) {
    levels.push_back({{"level", level.level},
                      {"views", level.views},
                      {"resolution", level.resolution},
                      {"offset_radius", level.offset_radius},
                      {"pixel_size", level.pixel_size},
                      {"depth_step", level.depth_step},
                      {"rounding", level.rounding},
                      {"world_min", level.world_min},
                      {"world_max", level.world_max}});
  }
  return {{"guaranteed", certificate.guaranteed}, {"basis", certificate.basis}, {"levels", levels}};
}

std::string CertificateText(const Certificate& certificate) {
  std::string text = "certificate: " + certificate.basis + "\n";
  char line[512];
  for (const LevelCertificate& level : certificate.levels) {
    std::snprintf(line, sizeof line, "  %-10s %d views at %d px: ", level.level.c_str(),
                  level.views, level.resolution);
    text += line;
    if (level.offset_radius > 0) {
      std::snprintf(line, sizeof line,
                    "r %.6g covers D/2 + sqrt(3) max(pixel %.6g, depth step %.6g) + rounding %.3g",
                    level.offset_radius, level.pixel_size, level.depth_step, level.rounding);
    } else {
      std::snprintf(line, sizeof line, "no offset (r 0), pixel %.6g, depth step %.6g",
                    level.pixel_size, level.depth_step);
    }
    text += line;
    std::snprintf(line, sizeof line, "; world [%.6g %.6g %.6g] - [%.6g %.6g %.6g]\n",
                  level.world_min[0], level.world_min[1], level.world_min[2], level.world_max[0],
                  level.world_max[1], level.world_max[2]);
    text += line;
  }
  return text;
}

json StatsJson(const StepStats& stats) {
  json stages = json::object();
  for (const auto& stage : stats.stages) stages[std::string(ToString(stage.stage))] = stage.ms;
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
          {"primitive_radius", stats.primitive_radius},
          {"certificate", CertificateJson(stats.certificate)}};
}

namespace {

json PointJson(const Eigen::Vector3d& p) { return json::array({p.x(), p.y(), p.z()}); }

// The contact geometry (StepRequest::geometry), parallel to contacts and distance_pairs.
void AddGeometryJson(const StepResult& result, json& out) {
  json contact_geometry = json::array(), closest = json::array(), penetrations = json::array();
  for (const ContactGeometry& g : result.contact_geometry) {
    json points = json::array();
    for (int k = 0; k < g.num_points; ++k) points.push_back(PointJson(g.points[k]));
    contact_geometry.push_back({{"points", points},
                                {"normal_a", PointJson(g.normal_a)},
                                {"normal_b", PointJson(g.normal_b)},
                                {"coplanar", g.coplanar}});
  }
  for (const ClosestPoints& c : result.closest_points)
    closest.push_back({{"point_a", PointJson(c.point_a)}, {"point_b", PointJson(c.point_b)}});
  for (const Penetration& p : result.penetrations) {
    json entry = {{"objects", {p.object_a, p.object_b}}, {"closed", p.closed}};
    if (p.closed) {
      entry["depth"] = p.depth;
      entry["direction"] = PointJson(p.direction);
      entry["point_a"] = PointJson(p.point_a);
      entry["point_b"] = PointJson(p.point_b);
    }
    penetrations.push_back(entry);
  }
  out["contact_geometry"] = contact_geometry;
  out["closest_points"] = closest;
  out["penetrations"] = penetrations;
}

}  // namespace

json ResultJson(const StepResult& result, bool geometry) {
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
  json out = {{"contacts", contacts},
              {"distance_pairs", distance_pairs},
              {"pcs_objects", result.pcs_objects},
              {"pcs_primitives", pcs_primitives},
              {"object_pairs", pairs},
              {"stats", StatsJson(result.stats)}};
  if (geometry) AddGeometryJson(result, out);
  return out;
}

}  // namespace far::cli
