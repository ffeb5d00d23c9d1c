#include "study_report.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

namespace far_study {
namespace {

// CSV cells are plain: auto's reason loses its commas and quotes.
std::string CsvText(std::string text) {
  std::replace(text.begin(), text.end(), ',', ';');
  std::replace(text.begin(), text.end(), '"', '\'');
  return text;
}

// A count that is only known with a reference: empty cell without one.
std::string Checked(const Row& row, int64_t value) {
  return row.checked ? std::to_string(value) : "";
}

void WriteCsvHeader(std::ofstream& out) {
  out << "scene,family,kind,triangles,objects,steps,config,method,mechanism,resolution,output,"
         "distance,samples,step_ms_median,step_ms_p25,step_ms_p75,step_ms_min,step_ms_max,"
         "cpu_ms,ingest_ms";
  for (far::Stage stage : far::kStages) out << "," << far::ToString(stage) << "_ms";
  out << ",cull_ms,pcs_objects,pcs_primitives,object_pairs,pairs_considered,pairs_tested,"
         "subobject_input,contacts_total,reference_total,missed_total,false_positives_total,"
         "distance_pairs_total,distance_reference_total,distance_missed_total,"
         "distance_spurious_total,queries,draws,primitives_rendered,gl_prepare_ms,gl_passes_ms,"
         "gl_gpu_ms,object_pairs_total,"
         "pairs_considered_total,checked,checked_steps,method_run,method_reason\n";
}

void WriteCsvRow(std::ofstream& out, const SceneReport& report, const Row& r) {
  out << report.name << "," << ToString(report.family) << "," << ToString(report.kind) << ","
      << report.triangles << "," << report.objects << "," << report.steps << "," << r.config << ","
      << r.method << "," << r.mechanism << "," << r.resolution << "," << r.output << ","
      << (r.distance() && report.distance ? std::to_string(*report.distance) : "") << ","
      << r.samples << "," << r.ms_median << "," << r.ms_p25 << "," << r.ms_p75 << "," << r.ms_min
      << "," << r.ms_max << "," << r.cpu_ms << "," << r.ingest_ms;
  for (double ms : r.stage_ms) out << "," << ms;
  out << "," << r.cull_ms << "," << r.pcs_objects << "," << r.pcs_primitives << ","
      << r.object_pairs << "," << r.pairs_considered << "," << r.pairs_tested << ","
      << r.subobject_input << "," << r.contacts << "," << Checked(r, r.reference_contacts) << ","
      << Checked(r, r.missed) << "," << Checked(r, r.false_positives) << ",";
  if (r.distance()) {
    out << r.distance_pairs << "," << Checked(r, r.distance_reference) << ","
        << Checked(r, r.distance_missed) << "," << Checked(r, r.distance_spurious);
  } else {
    out << ",,,";
  }
  out << "," << r.queries << "," << r.draws << "," << r.primitives_rendered << ","
      << r.gl_prepare_ms << "," << r.gl_passes_ms << "," << r.gl_gpu_ms << ","
      << r.object_pairs_total << "," << r.pairs_considered_total << "," << (r.checked ? 1 : 0)
      << "," << r.checked_steps << "," << r.method_run << "," << CsvText(r.method_reason) << "\n";
}

// " (3 of 6 steps checked)" where the reference did not check every step the row ran.
std::string PartlyChecked(const Row& row) {
  if (!row.checked || row.checked_steps == row.samples) return "";
  return " (" + std::to_string(row.checked_steps) + " of " + std::to_string(row.samples) +
         " steps checked)";
}

std::string MethodCell(const Row& r) {
  std::string text = r.method;
  if (r.spec.method == far::Method::kAuto) text += " (ran " + RunsText(r) + ")";
  if (r.reference) text += " (reference)";
  return text;
}

}  // namespace

std::string RunLine(const RunInfo& info) {
  return "Command: `" + info.command +
         "` (Release build; see docs/study.md). Machine: GL_RENDERER `" + info.renderer +
         "`, CPU " + info.cpu + ", nproc " + std::to_string(info.cpus) + ". " + info.date +
         ". Whole run: " + Fixed(info.seconds / 60, 1) + " min.\n";
}

std::string Fixed(double value, int digits) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", digits, value);
  return text;
}

std::string Ms(double ms) { return Fixed(ms, ms < 1 ? 3 : ms < 10 ? 2 : ms < 100 ? 1 : 0); }

std::string Count(double value) {
  if (value >= 1e7) return Fixed(value / 1e6, 0) + "M";
  if (value >= 1e5) return Fixed(value / 1e3, 0) + "k";
  return Fixed(value, 0);
}

std::string Ratio(double value) { return Fixed(value, value < 10 ? 2 : 1) + "x"; }

std::string CheckedSteps(const Row& row) {
  if (!row.checked) return "none";
  if (row.checked_steps == row.samples) return "all " + std::to_string(row.samples);
  return std::to_string(row.checked_steps) + " of " + std::to_string(row.samples);
}

std::string Misses(const Row& row) {
  if (!row.checked) return "not checked";
  return std::to_string(row.missed) + " / " + std::to_string(row.false_positives) +
         PartlyChecked(row);
}

std::string DistanceMisses(const Row& row) {
  if (!row.distance()) return "-";
  if (!row.checked) return "not checked";
  return std::to_string(row.distance_missed) + " / " + std::to_string(row.distance_spurious) +
         PartlyChecked(row);
}

std::string StageText(const Row& r) {
  std::ostringstream text;
  text << "ingest " << Ms(r.ingest_ms);
  for (far::Stage stage : far::kStages) {
    const double ms = r.stage_ms[StageIndex(stage)];
    if (ms >= 0.005) text << ", " << far::ToString(stage) << " " << Ms(ms);
  }
  // The GPU methods' views inside the culling stages (StepStats::gl_*_ms).
  if (r.gl_passes_ms > 0) {
    text << "; GL views: prepare " << Ms(r.gl_prepare_ms) << ", passes " << Ms(r.gl_passes_ms)
         << " (GPU " << Ms(r.gl_gpu_ms) << ")";
  }
  return text.str();
}

std::string RunsText(const Row& row) {
  std::vector<std::pair<int, std::string>> runs;
  for (const auto& [name, count] : row.runs) runs.emplace_back(-count, name);
  std::sort(runs.begin(), runs.end());
  std::string text;
  for (const auto& [count, name] : runs) {
    text += (text.empty() ? "" : ", ") + name + " x" + std::to_string(-count);
  }
  return text.empty() ? "-" : text;
}

bool WriteCsv(const std::string& path, const std::vector<SceneReport>& reports) {
  std::ofstream out(path);
  WriteCsvHeader(out);
  for (const SceneReport& report : reports) {
    for (const Row& r : report.rows) WriteCsvRow(out, report, r);
  }
  out.close();
  return static_cast<bool>(out);
}

std::string SceneTable(const SceneReport& report) {
  std::ostringstream md;
  md << "| method | mechanism | res | output | ms/step median [p25-p75] | CPU ms | ingest | update "
        "| object cull | SAP | prim cull | exact | PCS obj | PCS prims | obj pairs | tri pairs | "
        "contacts | missed | false pos | checked steps | dist pairs | dist missed / spurious | "
        "queries | draws |\n"
     << "|---|---|--:|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"
        "--:|--:|\n";
  for (const Row& r : report.rows) {
    md << "| " << MethodCell(r) << " | " << r.mechanism << " | "
       << (r.resolution > 0 ? std::to_string(r.resolution) : "-") << " | " << r.output << " | "
       << Ms(r.ms_median) << " [" << Ms(r.ms_p25) << "-" << Ms(r.ms_p75) << "] | " << Ms(r.cpu_ms)
       << " | " << Ms(r.ingest_ms);
    for (double ms : r.stage_ms) md << " | " << Ms(ms);
    md << " | " << Count(r.pcs_objects) << " | " << Count(r.pcs_primitives) << " | "
       << Count(r.object_pairs) << " | " << Count(r.pairs_considered) << " | " << r.contacts
       << " | " << (r.checked ? std::to_string(r.missed) : "not checked") << " | "
       << (r.checked ? std::to_string(r.false_positives) : "not checked") << " | "
       << CheckedSteps(r) << " | " << (r.distance() ? std::to_string(r.distance_pairs) : "-")
       << " | " << DistanceMisses(r) << " | " << Count(r.queries) << " | " << Count(r.draws)
       << " |\n";
  }
  return md.str();
}

std::string ScalingTable(const std::vector<SceneReport>& reports) {
  // Columns: every contacts configuration run on some size, in the order first met.
  std::vector<std::string> configs;
  std::vector<const SceneReport*> sizes;
  for (const SceneReport& report : reports) {
    if (report.family != Family::kScaling) continue;
    sizes.push_back(&report);
    for (const Row& row : report.rows) {
      const bool shown = !row.distance() || row.reference;  // the reference may ask for distance
      if (shown && std::find(configs.begin(), configs.end(), row.config) == configs.end())
        configs.push_back(row.config);
    }
  }
  if (sizes.empty() || configs.empty()) return "";
  std::ostringstream md;
  md << "| scene | triangles | objects";
  for (const std::string& config : configs) md << " | " << config << " ms";
  md << " | fcl / bvh | bvh contacts missed / spurious |\n|---|--:|--:";
  for (size_t i = 0; i < configs.size() + 2; ++i) md << "|--:";
  md << "|\n";
  for (const SceneReport* report : sizes) {
    md << "| " << report->name << " | " << report->triangles << " | " << report->objects;
    for (const std::string& config : configs) {
      const Row* row = Find(*report, config);
      if (row == nullptr && config == "exact")
        row = Find(*report, config, far::Output::kDistancePairs);
      md << " | " << (row && row->samples > 0 ? Ms(row->ms_median) : "-");
    }
    const Row* fcl = Find(*report, "fcl");
    const Row* bvh = Find(*report, "bvh");
    md << " | " << (fcl && bvh ? Ratio(fcl->ms_median / bvh->ms_median) : "-") << " | "
       << (bvh ? Misses(*bvh) : "-") << " |\n";
  }
  return md.str();
}

bool Plot(const std::string& script, const std::string& csv, const std::string& png) {
  const std::string command =
      "gnuplot -e \"csv='" + csv + "'; png='" + png + "'\" '" + script + "'";
  if (std::system(command.c_str()) != 0) {
    std::fprintf(stderr, "far-study: the plot failed: %s\n", command.c_str());
    return false;
  }
  std::printf("wrote %s\n", png.c_str());
  return true;
}

bool WriteResultsSection(const std::string& path, const std::string& section) {
  const std::string begin = "<!-- study:begin -->", end = "<!-- study:end -->";
  std::string text;
  {
    std::ifstream in(path);
    if (in) {
      std::ostringstream all;
      all << in.rdbuf();
      text = all.str();
    } else {
      text = "# Benchmark results\n";
    }
  }
  const std::string block = begin + "\n" + section + end + "\n";
  const auto b = text.find(begin), e = text.find(end);
  if (b != std::string::npos && e != std::string::npos && e > b) {
    auto after = e + end.size();
    if (after < text.size() && text[after] == '\n') ++after;
    text.replace(b, after - b, block);
  } else {
    if (!text.empty() && text.back() != '\n') text += "\n";
    text += "\n" + block;
  }
  std::ofstream out(path);
  out << text;
  return static_cast<bool>(out);
}

}  // namespace far_study
