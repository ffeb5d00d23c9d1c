// far-study: what each culling configuration costs and what it misses, on animated scenes.
//
// Scenes (study_scenes.h): the small ones (soup, bunnies, leaves, bunnies-fine), the paper-scale
// workloads (paper-leaves, breaking, paper-bunnies) and the scaling family (scaling-<triangles>).
// Configurations (study_run.h): aabb, bvh, auto, GPU configurations by scene family, fcl, a
// distance pass on the larger scenes, and the brute-force reference (exact); each owns its own
// Pipeline on one shared GL context, gets the same updates, and all run interleaved within
// every step. Outputs (study_report.h, study_bars.h): a CSV, two PNGs through gnuplot, and with
// --results the tables and the bars in bench/RESULTS.md between <!-- study:begin --> and
// <!-- study:end -->. See docs/study.md.

#include <sched.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "study_bars.h"
#include "study_report.h"
#include "study_run.h"
#include "study_scenes.h"
#include <CLI/CLI.hpp>

#include "far/gpu/gl_context.h"
#include "far/model/step_request.h"

#ifndef FAR_STUDY_DATA_DIR
#define FAR_STUDY_DATA_DIR "bench/data"
#endif
#ifndef FAR_STUDY_PLOT_DIR
#define FAR_STUDY_PLOT_DIR "bench/study"
#endif

namespace {

using Clock = std::chrono::steady_clock;
using far_study::Family;
using far_study::Row;
using far_study::SceneReport;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

struct Options {
  std::string scenes =
      "soup,bunnies,leaves,bunnies-fine,paper-leaves,breaking,paper-bunnies,scaling";
  std::string scaling_sizes = "5000,10000,20000,50000,100000,200000,300000";
  std::string resolutions = "256,512,1024,2048";
  std::string paper_gpu =
      "far/id-buffer/256,far/occlusion-query/256,far-exact-offset/id-buffer/256,"
      "far-exact-offset/occlusion-query/256,cullide/id-buffer/256";
  std::string scaling_gpu = "far/id-buffer/256";
  std::string methods;
  std::string distance = "paper";
  int repeat = 1;
  std::string csv_path, png_path, scaling_png_path, results_path;
  std::string plot_script = std::string(FAR_STUDY_PLOT_DIR) + "/plot_study.gp";
  std::string scaling_plot_script = std::string(FAR_STUDY_PLOT_DIR) + "/plot_scaling.gp";
  bool quick = false;
  far::GlPlatform gl_platform = far::GlPlatform::kAuto;  // device: a GPU run must not fall back
  far_study::SceneOptions scene;
  far_study::RunOptions run;
};

std::vector<std::string> Split(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, ',');) {
    if (!part.empty()) parts.push_back(part);
  }
  return parts;
}

// Parses a comma-separated list of integers in [low, high]; false (with a message) otherwise.
bool ParseInts(const std::string& flag, const std::string& text, long low, long high,
               std::vector<int>& values) {
  values.clear();
  for (const std::string& part : Split(text)) {
    char* end = nullptr;
    const long value = std::strtol(part.c_str(), &end, 10);
    if (end == part.c_str() || *end != '\0' || value < low || value > high) {
      std::fprintf(stderr, "far-study: %s: '%s' is not in [%ld, %ld]\n", flag.c_str(), part.c_str(),
                   low, high);
      return false;
    }
    values.push_back(static_cast<int>(value));
  }
  return true;
}

bool ParseGpuList(const std::string& flag, const std::string& text,
                  std::vector<far_study::ConfigSpec>& specs) {
  specs.clear();
  for (const std::string& part : Split(text)) {
    auto spec = far_study::ParseGpuConfig(part);
    if (!spec) {
      std::fprintf(stderr,
                   "far-study: %s: '%s' is not method/mechanism/resolution "
                   "(e.g. far/id-buffer/256)\n",
                   flag.c_str(), part.c_str());
      return false;
    }
    specs.push_back(*spec);
  }
  return true;
}

// The sizes of the scenes.
void AddSceneOptions(CLI::App& app, far_study::SceneOptions& scene) {
  app.add_option("--bunny", scene.bunny_path, "bunny mesh (OBJ/PLY/STL)")->capture_default_str();
  app.add_option("--bunny-subdivisions", scene.bunny_subdivisions,
                 "bunnies: midpoint subdivisions (x4 triangles each)")
      ->capture_default_str();
  app.add_option("--fine-subdivisions", scene.fine_extra_subdivisions,
                 "bunnies-fine: subdivisions beyond --bunny-subdivisions")
      ->capture_default_str();
  app.add_option("--fine-steps", scene.fine_steps, "bunnies-fine: measured steps")
      ->capture_default_str();
  app.add_option("--paper-bunny-refinement", scene.paper_bunny_refinement,
                 "paper-bunnies: RefineMesh n (n^2 x 3674 triangles per bunny)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  app.add_option("--breaking-static-triangles", scene.breaking_static_triangles,
                 "breaking: triangles of the terrain (at least)")
      ->check(CLI::Range(100, 10000000))
      ->capture_default_str();
  app.add_option("--breaking-rigid-triangles", scene.breaking_rigid_triangles,
                 "breaking: triangles of the vase (at least)")
      ->check(CLI::Range(100, 10000000))
      ->capture_default_str();
  app.add_option("--soup-objects", scene.soup_objects)->capture_default_str();
  app.add_option("--soup-triangles", scene.soup_triangles, "triangles per soup object")
      ->capture_default_str();
  app.add_option("--leaves", scene.leaves, "leaves: number of leaves")->capture_default_str();
  app.add_option("--leaf-cells", scene.leaf_cells, "leaves: a leaf is cells x cells quads")
      ->capture_default_str();
}

void AddOptions(CLI::App& app, Options& o) {
  app.add_option("--scenes", o.scenes,
                 "comma-separated: soup, bunnies, leaves, bunnies-fine, paper-leaves, breaking, "
                 "paper-bunnies, scaling (every --scaling-sizes), scaling-<triangles>")
      ->capture_default_str();
  app.add_option("--scaling-sizes", o.scaling_sizes, "triangles of the scaling family")
      ->capture_default_str();
  app.add_option("--steps", o.scene.steps, "measured steps per scene (plus a warm-up step)")
      ->capture_default_str();
  app.add_option("--repeat", o.repeat, "multiplies the measured steps (the animation goes on)")
      ->capture_default_str();
  app.add_option("--resolutions", o.resolutions, "viewport sizes of the small scenes' GPU configs")
      ->capture_default_str();
  app.add_option("--paper-gpu", o.paper_gpu, "GPU configurations of the paper-scale scenes")
      ->capture_default_str();
  app.add_option("--scaling-gpu", o.scaling_gpu, "GPU configurations of the scaling scenes")
      ->capture_default_str();
  app.add_option("--scaling-gpu-max", o.run.scaling_gpu_max,
                 "scaling sizes (triangles) up to which the GPU configurations run")
      ->capture_default_str();
  app.add_option("--scaling-reference-max", o.run.scaling_reference_max,
                 "scaling sizes up to which exact runs (beyond: misses not checked)")
      ->capture_default_str();
  app.add_option("--methods", o.methods,
                 "run only these methods (comma-separated; the reference always runs)");
  app.add_option("--distance", o.distance,
                 "distance pass: none, paper (paper-scale scenes), all (and scaling sizes)")
      ->check(CLI::IsMember({"none", "paper", "all"}))
      ->capture_default_str();
  app.add_option("--distance-fraction", o.run.distance_fraction,
                 "D of the distance pass as a fraction of the diagonal of the scene's world box "
                 "at step 0")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--reference-steps", o.run.reference_steps,
                 "run the brute-force reference on N measured steps of each scene only, spread "
                 "evenly (breaking: also the break and the step after it); 0: every step")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--oq-steps", o.run.oq_steps,
                 "run occlusion-query configurations on the first N measured steps only (0: all)")
      ->capture_default_str();
  app.add_option("--csv", o.csv_path, "write one row per scene and configuration");
  app.add_option("--png", o.png_path, "plot per scene (default: the CSV path with .png)");
  app.add_option("--scaling-png", o.scaling_png_path,
                 "plot of the scaling family (default: <CSV stem>_scaling.png)");
  app.add_option("--results", o.results_path, "replace the study section of this Markdown file");
  app.add_option("--plot-script", o.plot_script, "gnuplot script")->capture_default_str();
  app.add_option("--scaling-plot-script", o.scaling_plot_script)->capture_default_str();
  AddSceneOptions(app, o.scene);
  app.add_flag("--quick", o.quick,
               "smoke test: small scenes and scaling 2000,5000 (with the distance pass), 2 steps, "
               "resolutions 256,1024");
  app.add_option_function<std::string>(
         "--gl-platform",
         [&o](const std::string& name) { o.gl_platform = *far::ParseGlPlatform(name); },
         "EGL platform: auto, device (a GPU only: fails without one) or surfaceless")
      ->check([](const std::string& name) {
        return far::ParseGlPlatform(name)
                   ? std::string()
                   : "unknown platform '" + name + "' (" + far::GlPlatformNames() + ")";
      });
}

// --quick: small sizes, unless a flag set them explicitly.
void ApplyQuick(const CLI::App& app, Options& o) {
  if (app.count("--scenes") == 0) o.scenes = "soup,bunnies,leaves,bunnies-fine,scaling";
  if (app.count("--scaling-sizes") == 0) o.scaling_sizes = "2000,5000";
  if (app.count("--steps") == 0) o.scene.steps = 2;
  if (app.count("--resolutions") == 0) o.resolutions = "256,1024";
  if (app.count("--distance") == 0) o.distance = "all";  // the tiny scaling sizes check it
  o.scene.bunny_subdivisions = 0;
  o.scene.fine_extra_subdivisions = 0;
  o.scene.fine_steps = 1;
  o.scene.soup_objects = 16;
  o.scene.leaves = 30;
  o.scene.leaf_cells = 4;
}

// Checks and converts the flags; the scene names with "scaling" expanded. Exit status 2 on error.
int Prepare(const CLI::App& app, Options& o, std::vector<std::string>& scenes) {
  if (o.quick) ApplyQuick(app, o);
  std::vector<int> sizes;
  if (!ParseInts("--resolutions", o.resolutions, 8, 8192, o.run.resolutions) ||
      !ParseInts("--scaling-sizes", o.scaling_sizes, 1000, 10000000, sizes) ||
      !ParseGpuList("--paper-gpu", o.paper_gpu, o.run.paper_gpu) ||
      !ParseGpuList("--scaling-gpu", o.scaling_gpu, o.run.scaling_gpu)) {
    return 2;
  }
  for (const std::string& name : Split(o.methods)) {
    if (!far::ParseMethod(name)) {
      std::fprintf(stderr, "far-study: --methods: unknown method '%s' (%s)\n", name.c_str(),
                   far::MethodNames().c_str());
      return 2;
    }
    o.run.methods.insert(name);
  }
  for (const std::string& name : Split(o.scenes)) {
    if (name == "scaling") {
      for (int size : sizes) scenes.push_back("scaling-" + std::to_string(size));
    } else if (far_study::IsKnownScene(name)) {
      scenes.push_back(name);
    } else {
      std::fprintf(stderr, "far-study: unknown scene '%s'\n", name.c_str());
      return 2;
    }
  }
  if (o.scene.steps < 1 || o.repeat < 1 || o.run.resolutions.empty()) {
    std::fprintf(stderr, "far-study: --steps, --repeat and --resolutions must be positive\n");
    return 2;
  }
  o.scene.steps *= o.repeat;
  o.run.distance_on_paper = o.distance != "none";
  o.run.distance_on_scaling = o.distance == "all";
  const std::filesystem::path csv(o.csv_path);
  if (!o.csv_path.empty() && o.png_path.empty())
    o.png_path = std::filesystem::path(csv).replace_extension(".png").string();
  if (!o.csv_path.empty() && o.scaling_png_path.empty())
    o.scaling_png_path = (csv.parent_path() / (csv.stem().string() + "_scaling.png")).string();
  // The outputs' folders now, not after a run of many minutes.
  for (const std::string& path : {o.csv_path, o.png_path, o.scaling_png_path, o.results_path}) {
    const auto folder = std::filesystem::path(path).parent_path();
    std::error_code error;
    if (path.empty() || folder.empty()) continue;
    if (!std::filesystem::create_directories(folder, error) && error) {
      std::fprintf(stderr, "far-study: cannot make the folder of %s: %s\n", path.c_str(),
                   error.message().c_str());
      return 2;
    }
  }
  return 0;
}

std::string ReadFirstLine(const std::string& path, const std::string& key) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key, 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(line.find_first_not_of(" \t", colon + 1));
    }
  }
  return "unknown";
}

int AvailableCpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) != 0) return 0;
  return CPU_COUNT(&set);
}

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char text[64];
  std::strftime(text, sizeof(text), "%Y-%m-%d %H:%M UTC", &tm);
  return text;
}

std::string CommandLine(int argc, char** argv) {
  std::string command = "far-study";
  for (int i = 1; i < argc; ++i) command += std::string(" ") + argv[i];
  return command;
}

// Reliability: a reliable method misses nothing, an exact-stage method (all but fcl) reports
// no contact or distance pair the reference does not have. Prints each problem.
int CountProblems(const std::vector<SceneReport>& reports) {
  int problems = 0;
  for (const SceneReport& report : reports) {
    for (const Row& row : report.rows) {
      if (!row.checked) continue;
      const bool misses =
          far::IsReliable(row.spec.method) && (row.missed > 0 || row.distance_missed > 0);
      const bool spurious = row.spec.method != far::Method::kFcl &&
                            (row.false_positives > 0 || row.distance_spurious > 0);
      if (!misses && !spurious) continue;
      std::printf(
          "PROBLEM: %s %s (%s): missed %lld, false positives %lld; distance pairs missed "
          "%lld, spurious %lld\n",
          report.name.c_str(), row.config.c_str(), row.output.c_str(),
          static_cast<long long>(row.missed), static_cast<long long>(row.false_positives),
          static_cast<long long>(row.distance_missed),
          static_cast<long long>(row.distance_spurious));
      ++problems;
    }
  }
  return problems;
}

// A path as the Markdown file at `results` links it.
std::string LinkFrom(const std::string& results, const std::string& path) {
  const auto dir = std::filesystem::absolute(results).parent_path();
  return std::filesystem::absolute(path).lexically_proximate(dir).string();
}

std::string ResultsSection(const std::vector<SceneReport>& reports, const far_study::Bars& bars,
                           const far_study::RunInfo& info, const Options& o, int problems) {
  std::ostringstream md;
  md << "## Accuracy and cost study (far-study)\n\n"
     << far_study::RunLine(info) << "\n"
     << "Time per step = ingest (`Pipeline::Apply` of the step's updates into that "
        "configuration's own pipeline) + `Pipeline::Step`, wall clock, median over the measured "
        "steps with the interquartile range; stage columns are medians of the pipeline's own "
        "stage timers. All configurations of a scene ran interleaved within each step, each with "
        "its own pipeline and the same updates. Counts are medians per step; contacts, missed and "
        "false positives are totals over the steps the brute-force reference (`exact`) checked, "
        "named above each scene's table (where the distance pass runs, one exact run with output "
        "distance answers both contacts and distance pairs). \"tri pairs\" are the candidate "
        "triangle pairs that reach the exact stage's prefilter (pairs_considered).\n\n"
     << "### Bars\n\n"
     << bars.table << "\n";
  if (problems > 0) md << "**" << problems << " reliability problems: see the tables.**\n\n";
  md << bars.sections;
  const std::string scaling = far_study::ScalingTable(reports);
  if (!scaling.empty()) {
    md << "### Scaling family: time per step against triangles\n\n"
       << far_study::RunLine(info)
       << "\nMedian ms per step (contacts) of every configuration at every size of "
          "`ScalingScene`; `exact` is the reference (with the distance pass it also finds the "
          "distance pairs), \"-\" where a configuration did not run at that size.\n\n"
       << scaling << "\n";
    if (!o.scaling_png_path.empty())
      md << "![time per step against triangles](" << LinkFrom(o.results_path, o.scaling_png_path)
         << ")\n\n";
  }
  md << "### Every scene and configuration\n\n" << far_study::RunLine(info) << "\n";
  if (!o.png_path.empty()) {
    md << "![time per step against missed contacts and PCS size]("
       << LinkFrom(o.results_path, o.png_path) << ")\n\nCSV: `" << o.csv_path << "`.\n\n";
  }
  for (const SceneReport& report : reports) {
    md << "#### " << report.name << ": " << report.description << "; " << report.steps
       << " measured steps"
       << (report.distance ? ", distance D = " + far_study::Fixed(*report.distance, 4) : "")
       << "\n\nReference: " << report.ReferenceText() << ".\n\n"
       << far_study::SceneTable(report) << "\n";
  }
  return md.str();
}

// Builds and runs every scene in order. False (with a message) when one cannot be made or run.
bool RunScenes(const std::vector<std::string>& scenes, const Options& o,
               std::vector<SceneReport>& reports) {
  for (const std::string& name : scenes) {
    auto scene = far_study::MakeStudyScene(name, o.scene);
    if (!scene.ok()) {
      std::fprintf(stderr, "far-study: %s: %s\n", name.c_str(), scene.error().message.c_str());
      return false;
    }
    std::printf("scene %s: %s (%lld triangles)\n", name.c_str(), scene->description.c_str(),
                static_cast<long long>(scene->triangles));
    auto report = far_study::RunScene(*scene, o.run);
    if (!report.ok()) {
      std::fprintf(stderr, "far-study: %s: %s\n", name.c_str(), report.error().message.c_str());
      return false;
    }
    std::printf("  %s done in %.1f s\n", name.c_str(), report->seconds);
    reports.push_back(std::move(*report));
  }
  return true;
}

// CSV, plots (a plot that fails is not linked from the results) and the results section.
bool WriteOutputs(const std::vector<SceneReport>& reports, const far_study::Bars& bars,
                  const far_study::RunInfo& info, Options o, int problems) {
  if (o.csv_path.empty()) {
    o.png_path.clear();
    o.scaling_png_path.clear();
  } else {
    if (!far_study::WriteCsv(o.csv_path, reports)) {
      std::fprintf(stderr, "far-study: cannot write %s\n", o.csv_path.c_str());
      return false;
    }
    std::printf("wrote %s\n", o.csv_path.c_str());
    if (!o.png_path.empty() && !far_study::Plot(o.plot_script, o.csv_path, o.png_path))
      o.png_path.clear();
    if (!o.scaling_png_path.empty() &&
        (far_study::ScalingTable(reports).empty() ||
         !far_study::Plot(o.scaling_plot_script, o.csv_path, o.scaling_png_path))) {
      o.scaling_png_path.clear();
    }
  }
  if (o.results_path.empty()) return true;
  if (!far_study::WriteResultsSection(o.results_path,
                                      ResultsSection(reports, bars, info, o, problems))) {
    std::fprintf(stderr, "far-study: cannot write %s\n", o.results_path.c_str());
    return false;
  }
  std::printf("wrote the study section of %s\n", o.results_path.c_str());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  o.scene.bunny_path = std::string(FAR_STUDY_DATA_DIR) + "/bunny.obj";
  CLI::App app{
      "far-study: cost and accuracy of every culling configuration, and FCL, on animated "
      "scenes (see docs/study.md)"};
  AddOptions(app, o);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help is a ParseError with exit code 0; every bad flag is exit status 2 (docs/study.md).
    return app.exit(e) == 0 ? 0 : 2;
  }
  std::vector<std::string> scenes;
  if (const int status = Prepare(app, o, scenes); status != 0) return status;

  // One GL context for every configuration's pipeline.
  auto context = far::GlContext::Create(o.gl_platform);
  if (!context.ok()) {
    std::fprintf(stderr, "far-study: no GL context: %s\n", context.error().message.c_str());
    return 1;
  }
  far_study::RunInfo info;
  info.command = CommandLine(argc, argv);
  info.renderer = (*context)->renderer();
  info.cpu = ReadFirstLine("/proc/cpuinfo", "model name");
  info.cpus = AvailableCpus();
  std::printf("GL_RENDERER: %s\nCPU: %s, %d available\n", info.renderer.c_str(), info.cpu.c_str(),
              info.cpus);

  std::vector<SceneReport> reports;
  const auto study_start = Clock::now();
  if (!RunScenes(scenes, o, reports)) return 1;
  info.seconds = SecondsSince(study_start);
  info.date = UtcNow();

  const int problems = CountProblems(reports);
  const far_study::Bars bars = far_study::EvaluateBars(reports, o.run, info);
  for (const SceneReport& report : reports)
    std::printf("\n### %s\nReference: %s.\n%s", report.name.c_str(), report.ReferenceText().c_str(),
                far_study::SceneTable(report).c_str());
  std::printf("\n%s", bars.summary.c_str());
  if (!WriteOutputs(reports, bars, info, o, problems)) return 1;
  return problems > 0 ? 3 : 0;
}
