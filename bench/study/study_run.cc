#include "study_run.h"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iterator>
#include <memory>
#include <numeric>
#include <sstream>
#include <utility>
#include <variant>

#include <Eigen/Geometry>

#include "far/base/quantile.h"
#include "far/base/thread_pool.h"
#include "far/model/scene_update.h"
#include "far/model/slot_ids.h"
#include "far/pairs/exact_stage.h"
#include "far/pipeline/pipeline.h"

namespace far_study {
namespace {

using Clock = std::chrono::steady_clock;

double MillisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// CPU time of the whole process (every thread: llvmpipe's rasterizer threads, the exact-test
// pool), in ms. On a machine shared with other work it measures the work a step did, where
// wall time also counts the time spent waiting for a core.
double ProcessCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

ConfigSpec Cpu(far::Method method, far::Output output = far::Output::kContacts) {
  return {method, std::nullopt, 0, output};
}

// The GPU configurations of a scene by family (before the --methods filter).
std::vector<ConfigSpec> GpuConfigs(const StudyScene& scene, const RunOptions& options) {
  std::vector<ConfigSpec> configs;
  if (scene.family == Family::kPaper) return options.paper_gpu;
  if (scene.family == Family::kScaling) {
    if (scene.nominal_triangles <= options.scaling_gpu_max) return options.scaling_gpu;
    return {};
  }
  std::vector<far::Method> methods = {far::Method::kCullide, far::Method::kFar,
                                      far::Method::kFarExactOffset};
  std::vector<int> resolutions = options.resolutions;
  if (scene.far_only) {
    methods = {far::Method::kFar};
    resolutions = {options.PrimaryResolution()};
  }
  for (far::Method method : methods) {
    for (far::QueryMechanism mechanism :
         {far::QueryMechanism::kIdBuffer, far::QueryMechanism::kOcclusionQuery}) {
      for (int resolution : resolutions)
        configs.push_back({method, mechanism, resolution, far::Output::kContacts});
    }
  }
  return configs;
}

bool Wanted(const ConfigSpec& spec, const RunOptions& options) {
  return options.methods.empty() || options.methods.count(std::string(far::ToString(spec.method)));
}

// The distance pass: aabb, bvh, one FAR configuration and the reference, output distance.
bool RunsDistance(const StudyScene& scene, const RunOptions& options) {
  return (scene.family == Family::kPaper && options.distance_on_paper) ||
         (scene.family == Family::kScaling && options.distance_on_scaling);
}

template <typename T>
int64_t CountMissing(const std::vector<T>& expected, const std::vector<T>& found) {
  std::vector<T> missing;
  std::set_difference(expected.begin(), expected.end(), found.begin(), found.end(),
                      std::back_inserter(missing));
  return static_cast<int64_t>(missing.size());
}

// The reference: far::BruteForceReference, the oracle of the tests, on the study's own copy of
// the scene, outside any pipeline: a pipeline may refuse method 'exact' on a large scene, and the
// study needs the reference on every scene it checks.
class BruteForceScene {
 public:
  explicit BruteForceScene(const far::Scene& scene) {
    for (const auto& object : scene.objects) objects_[object.id] = object;
  }

  void Apply(far::FrameUpdate frame) {
    for (uint32_t id : frame.removals) objects_.erase(id);
    for (auto& object : frame.additions) objects_[object.id] = std::move(object);
    for (const auto& [id, pose] : frame.poses) objects_.at(id).X_WO = pose;
    for (auto& [id, mesh] : frame.vertices) objects_.at(id).mesh.p_MV = std::move(mesh.p_MV);
  }

  // Contacts (and distance pairs within `distance`) of every cross-object triangle pair, with
  // the culling outputs implied by them, as the pipeline's exact method reports them.
  far::StepResult Step(std::optional<double> distance) {
    const auto start = Clock::now();
    std::vector<std::vector<Eigen::Vector3d>> p_WV;
    p_WV.reserve(objects_.size());
    for (const auto& [id, object] : objects_) {
      const Eigen::Isometry3d X_WO = object.X_WO.ToIsometry();
      auto& points = p_WV.emplace_back();
      points.reserve(object.mesh.p_MV.size());
      for (const auto& p : object.mesh.p_MV) points.push_back(far::WorldVertex(X_WO, p));
    }
    std::vector<far::WorldObjectView> views;
    std::vector<uint32_t> ids;  // by slot
    for (const auto& [id, object] : objects_) {
      views.push_back({p_WV[views.size()], object.mesh.triangles});
      ids.push_back(id);
    }
    far::StepResult result;
    result.stats.method = "exact";
    result.stats.stages.push_back({far::Stage::kUpdate, MillisecondsSince(start)});
    const auto exact_start = Clock::now();
    far::ExactResult exact = far::BruteForceReference(views, distance, pool_);
    result.stats.stages.push_back({far::Stage::kExact, MillisecondsSince(exact_start)});
    result.stats.pairs_considered = static_cast<int64_t>(exact.pairs_considered);
    result.stats.pairs_tested = static_cast<int64_t>(exact.pairs_tested);
    const far::SlotIds slot_ids(ids);
    result.contacts = slot_ids.WithIds(exact.contacts);
    result.distance_pairs = slot_ids.WithIds(exact.distance_pairs);
    DeriveCullingOutputs(result);
    return result;
  }

 private:
  // Object PCS, object pairs and primitive PCS: the objects and triangles in some pair.
  static void DeriveCullingOutputs(far::StepResult& result) {
    std::set<uint32_t> pcs;
    std::set<far::ObjectPair> pairs;
    std::map<uint32_t, std::set<uint32_t>> primitives;
    auto note = [&](const far::ContactPair& c) {
      pcs.insert({c.object_a, c.object_b});
      pairs.insert({c.object_a, c.object_b});
      primitives[c.object_a].insert(c.triangle_a);
      primitives[c.object_b].insert(c.triangle_b);
    };
    for (const auto& c : result.contacts) note(c);
    for (const auto& d : result.distance_pairs) note(d.pair);
    for (const auto& [id, triangles] : primitives)
      result.pcs_primitives[id].assign(triangles.begin(), triangles.end());
    result.pcs_objects.assign(pcs.begin(), pcs.end());
    result.object_pairs.assign(pairs.begin(), pairs.end());
  }

  std::map<uint32_t, far::SceneObject> objects_;
  far::ThreadPool pool_;  // as many threads as a pipeline's pool
};

// A configuration while the scene runs: a pipeline, or the reference's brute force.
struct Live {
  ConfigSpec spec;
  bool reference = false;
  std::unique_ptr<far::Pipeline> pipeline;
  std::unique_ptr<BruteForceScene> brute_force;
  std::vector<Sample> samples;
  // The answer of the current step (compared once every configuration ran).
  std::vector<far::ContactPair> contacts;
  std::vector<far::DistancePair> distance_pairs;
};

far::Result<std::vector<Live>> MakePipelines(const StudyScene& scene,
                                             const std::vector<ConfigSpec>& specs,
                                             bool has_reference) {
  std::vector<Live> live;
  for (size_t i = 0; i < specs.size(); ++i) {
    Live config;
    config.spec = specs[i];
    config.reference = has_reference && i + 1 == specs.size();
    if (config.reference) {
      config.brute_force = std::make_unique<BruteForceScene>(scene.scene);
      live.push_back(std::move(config));
      continue;
    }
    far::PipelineOptions pipeline_options;
    pipeline_options.use_current_context = true;  // the study's one context
    auto pipeline = far::Pipeline::Create(pipeline_options);
    if (!pipeline.ok()) return pipeline.error();
    if (auto loaded = (*pipeline)->LoadScene(scene.scene); !loaded.ok()) return loaded.error();
    config.pipeline = std::move(*pipeline);
    live.push_back(std::move(config));
  }
  return live;
}

far::StepRequest RequestFor(const ConfigSpec& spec, std::optional<double> distance) {
  far::StepRequest request;
  request.method = spec.method;
  if (spec.mechanism) request.mechanism = *spec.mechanism;
  if (spec.resolution > 0) request.resolution = spec.resolution;
  request.output = spec.output;
  if (spec.output == far::Output::kDistancePairs) request.distance = distance;
  return request;
}

// What a step's result says, apart from the times.
void Record(far::StepResult& result, const std::map<uint32_t, int64_t>& triangles_of,
            Sample& sample) {
  for (const auto& stage : result.stats.stages)
    sample.stage_ms[StageIndex(stage.stage)] += stage.ms;
  sample.cull_ms = sample.stage_ms[StageIndex(far::Stage::kObjectCull)] +
                   sample.stage_ms[StageIndex(far::Stage::kPrimitiveCull)];
  sample.pcs_objects = static_cast<int64_t>(result.pcs_objects.size());
  for (const auto& [id, triangles] : result.pcs_primitives)
    sample.pcs_primitives += static_cast<int64_t>(triangles.size());
  sample.object_pairs = static_cast<int64_t>(result.object_pairs.size());
  std::set<uint32_t> paired;
  for (const auto& pair : result.object_pairs) paired.insert({pair.object_a, pair.object_b});
  for (uint32_t id : paired) sample.subobject_input += triangles_of.at(id);
  sample.pairs_considered = result.stats.pairs_considered;
  sample.pairs_tested = result.stats.pairs_tested;
  sample.queries = result.stats.queries;
  sample.draws = result.stats.draws;
  sample.primitives_rendered = result.stats.primitives_rendered;
  sample.gl_prepare_ms = result.stats.gl_prepare_ms;
  sample.gl_passes_ms = result.stats.gl_passes_ms;
  sample.gl_gpu_ms = result.stats.gl_gpu_ms;
  sample.gpu_filter = result.stats.gpu_filter;
  sample.contacts = static_cast<int64_t>(result.contacts.size());
  sample.distance_pairs = static_cast<int64_t>(result.distance_pairs.size());
  sample.method_run = result.stats.method;
  sample.method_reason = result.stats.method_reason;
}

// One configuration at one step: the updates (copied before the clock starts: copying is the
// caller's cost), then the step unless `run` is false. Returns whether it ran.
far::Result<bool> RunOne(Live& config, const far::FrameUpdate* frame, bool run,
                         std::optional<double> distance,
                         const std::map<uint32_t, int64_t>& triangles_of, Sample& sample) {
  std::vector<far::SceneUpdate> updates;
  far::FrameUpdate copy;
  if (frame != nullptr && config.brute_force) copy = *frame;
  if (frame != nullptr && !config.brute_force) updates = ToUpdates(*frame);
  const auto start = Clock::now();
  const double cpu_start = ProcessCpuMs();
  if (config.brute_force) {
    config.brute_force->Apply(std::move(copy));
  } else if (auto ok = config.pipeline->Apply(std::move(updates)); !ok.ok()) {
    return ok.error();
  }
  const double ingest_ms = MillisecondsSince(start);
  if (!run) return false;
  far::Result<far::StepResult> result =
      config.brute_force ? far::Result<far::StepResult>(config.brute_force->Step(distance))
                         : config.pipeline->Step(RequestFor(config.spec, distance));
  sample.step_ms = MillisecondsSince(start);
  sample.cpu_ms = ProcessCpuMs() - cpu_start;
  if (!result.ok()) return result.error();
  sample.ingest_ms = ingest_ms;
  Record(*result, triangles_of, sample);
  config.contacts = std::move(result->contacts);
  config.distance_pairs = std::move(result->distance_pairs);
  return true;
}

// Misses and false positives of `config` against the reference's answer of the same step.
void Compare(const Live& reference, const Live& config, Sample& sample) {
  sample.checked = true;
  sample.reference = static_cast<int64_t>(reference.contacts.size());
  sample.missed = CountMissing(reference.contacts, config.contacts);
  sample.false_positives = CountMissing(config.contacts, reference.contacts);
  if (config.spec.output != far::Output::kDistancePairs) return;
  sample.distance_reference = static_cast<int64_t>(reference.distance_pairs.size());
  sample.distance_missed = CountMissing(reference.distance_pairs, config.distance_pairs);
  sample.distance_spurious = CountMissing(config.distance_pairs, reference.distance_pairs);
}

void TrackTriangles(const far::FrameUpdate& frame, std::map<uint32_t, int64_t>& triangles_of) {
  for (uint32_t id : frame.removals) triangles_of.erase(id);
  for (const auto& object : frame.additions) triangles_of[object.id] = object.mesh.num_triangles();
}

template <typename F>
double MedianOf(const std::vector<Sample>& samples, F field) {
  std::vector<double> values;
  for (const Sample& s : samples) values.push_back(static_cast<double>(field(s)));
  return far::Quantile(values, 0.5);
}

template <typename F>
int64_t SumOf(const std::vector<Sample>& samples, F field) {
  int64_t total = 0;
  for (const Sample& s : samples) total += field(s);
  return total;
}

void SummarizeTimes(const std::vector<Sample>& s, Row& row) {
  std::vector<double> ms;
  for (const Sample& x : s) {
    ms.push_back(x.step_ms);
    row.ms_by_step[x.step] = x.step_ms;
  }
  row.ms_median = far::Quantile(ms, 0.5);
  row.ms_p25 = far::Quantile(ms, 0.25);
  row.ms_p75 = far::Quantile(ms, 0.75);
  row.ms_min = far::Quantile(ms, 0);
  row.ms_max = far::Quantile(ms, 1);
  row.cpu_ms = MedianOf(s, [](const Sample& x) { return x.cpu_ms; });
  row.ingest_ms = MedianOf(s, [](const Sample& x) { return x.ingest_ms; });
  row.cull_ms = MedianOf(s, [](const Sample& x) { return x.cull_ms; });
  for (size_t i = 0; i < far::kStages.size(); ++i) {
    row.stage_ms[i] = MedianOf(s, [&](const Sample& x) { return x.stage_ms[i]; });
  }
}

void SummarizeCounts(const std::vector<Sample>& s, Row& row) {
  row.pcs_objects = MedianOf(s, [](const Sample& x) { return x.pcs_objects; });
  row.pcs_primitives = MedianOf(s, [](const Sample& x) { return x.pcs_primitives; });
  row.object_pairs = MedianOf(s, [](const Sample& x) { return x.object_pairs; });
  row.pairs_considered = MedianOf(s, [](const Sample& x) { return x.pairs_considered; });
  row.pairs_tested = MedianOf(s, [](const Sample& x) { return x.pairs_tested; });
  row.subobject_input = MedianOf(s, [](const Sample& x) { return x.subobject_input; });
  row.queries = MedianOf(s, [](const Sample& x) { return x.queries; });
  row.draws = MedianOf(s, [](const Sample& x) { return x.draws; });
  row.primitives_rendered = MedianOf(s, [](const Sample& x) { return x.primitives_rendered; });
  row.gl_prepare_ms = MedianOf(s, [](const Sample& x) { return x.gl_prepare_ms; });
  row.gl_passes_ms = MedianOf(s, [](const Sample& x) { return x.gl_passes_ms; });
  row.gl_gpu_ms = MedianOf(s, [](const Sample& x) { return x.gl_gpu_ms; });
  const auto filter = [&](auto field) {
    return MedianOf(s, [&](const Sample& x) { return static_cast<double>(x.gpu_filter.*field); });
  };
  row.gpu_box_pairs = filter(&far::GpuFilterCounters::box_pairs);
  row.gpu_float = filter(&far::GpuFilterCounters::float_decided);
  row.gpu_double = filter(&far::GpuFilterCounters::double_decided);
  row.gpu_cpu = filter(&far::GpuFilterCounters::sent_to_cpu);
  row.gpu_distance_culled = filter(&far::GpuFilterCounters::distance_culled);
  row.gpu_refit_ms = filter(&far::GpuFilterCounters::gpu_refit_ms);
  row.gpu_traverse_ms = filter(&far::GpuFilterCounters::gpu_traverse_ms);
  row.gpu_filter_ms = filter(&far::GpuFilterCounters::gpu_filter_ms);
  row.contacts = SumOf(s, [](const Sample& x) { return x.contacts; });
  row.reference_contacts = SumOf(s, [](const Sample& x) { return x.reference; });
  row.missed = SumOf(s, [](const Sample& x) { return x.missed; });
  row.false_positives = SumOf(s, [](const Sample& x) { return x.false_positives; });
  row.distance_pairs = SumOf(s, [](const Sample& x) { return x.distance_pairs; });
  row.distance_reference = SumOf(s, [](const Sample& x) { return x.distance_reference; });
  row.distance_missed = SumOf(s, [](const Sample& x) { return x.distance_missed; });
  row.distance_spurious = SumOf(s, [](const Sample& x) { return x.distance_spurious; });
  row.object_pairs_total = SumOf(s, [](const Sample& x) { return x.object_pairs; });
  row.pairs_considered_total = SumOf(s, [](const Sample& x) { return x.pairs_considered; });
}

Row Summarize(const Live& config) {
  Row row;
  row.spec = config.spec;
  row.config = config.spec.Name();
  row.method = std::string(far::ToString(config.spec.method));
  row.mechanism = config.spec.mechanism ? std::string(far::ToString(*config.spec.mechanism)) : "-";
  row.output = std::string(far::ToString(config.spec.output));
  row.resolution = config.spec.resolution;
  row.samples = static_cast<int>(config.samples.size());
  row.reference = config.reference;
  for (const Sample& x : config.samples) row.checked_steps += x.checked;
  row.checked = row.checked_steps > 0;
  SummarizeTimes(config.samples, row);
  SummarizeCounts(config.samples, row);
  for (const Sample& x : config.samples) ++row.runs[x.method_run];
  int most = 0;
  for (const auto& [name, count] : row.runs) {
    if (count > most) row.method_run = name, most = count;
  }
  if (!config.samples.empty()) row.method_reason = config.samples.back().method_reason;
  return row;
}

}  // namespace

std::string ConfigSpec::Name() const {
  std::string name(far::ToString(method));
  if (mechanism)
    name += "/" + std::string(far::ToString(*mechanism)) + "/" + std::to_string(resolution);
  return name;
}

std::optional<ConfigSpec> ParseGpuConfig(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, '/');) parts.push_back(part);
  if (parts.size() != 3) return std::nullopt;
  const auto method = far::ParseMethod(parts[0]);
  const auto mechanism = far::ParseMechanism(parts[1]);
  char* end = nullptr;
  const long resolution = std::strtol(parts[2].c_str(), &end, 10);
  if (!method || !far::IsGpuMethod(*method) || !mechanism || *end != '\0' || resolution < 8 ||
      resolution > 8192) {
    return std::nullopt;
  }
  return ConfigSpec{*method, *mechanism, static_cast<int>(resolution), far::Output::kContacts};
}

int RunOptions::PrimaryResolution() const {
  if (std::count(resolutions.begin(), resolutions.end(), 1024) > 0) return 1024;
  return resolutions.empty() ? 1024 : *std::max_element(resolutions.begin(), resolutions.end());
}

std::vector<ConfigSpec> ConfigsFor(const StudyScene& scene, const RunOptions& options,
                                   bool* has_reference) {
  using far::Method;
  // gpu has no mechanism or resolution: one configuration per scene, like the CPU methods.
  std::vector<ConfigSpec> all = {Cpu(Method::kAabb), Cpu(Method::kBvh), Cpu(Method::kGpu),
                                 Cpu(Method::kAuto)};
  const std::vector<ConfigSpec> gpu = GpuConfigs(scene, options);
  all.insert(all.end(), gpu.begin(), gpu.end());
  all.push_back(Cpu(Method::kFcl));
  const bool distance = RunsDistance(scene, options);
  if (distance) {
    for (Method method : {Method::kAabb, Method::kBvh, Method::kGpu})
      all.push_back(Cpu(method, far::Output::kDistancePairs));
    // FAR's distance pass: the first plain FAR configuration of the scene.
    for (const ConfigSpec& spec : gpu) {
      if (spec.method != Method::kFar) continue;
      ConfigSpec far = spec;
      far.output = far::Output::kDistancePairs;
      all.push_back(far);
      break;
    }
  }
  std::vector<ConfigSpec> configs;
  for (const ConfigSpec& spec : all) {
    if (Wanted(spec, options)) configs.push_back(spec);
  }
  *has_reference =
      scene.family != Family::kScaling || scene.nominal_triangles <= options.scaling_reference_max;
  if (*has_reference) {
    configs.push_back(
        Cpu(Method::kExact, distance ? far::Output::kDistancePairs : far::Output::kContacts));
  }
  return configs;
}

namespace {

// What every step of a scene shares: D of the distance pass and where the reference runs.
struct StepPlan {
  std::optional<double> distance;
  bool has_reference = false;     // configs.back() is the reference
  std::set<int> reference_steps;  // measured steps it runs on
};

// Runs every configuration once at step s (0: the warm-up, no frame, no reference: the brute
// force has nothing to warm up), in StepOrder, then compares each answer with the reference's
// where it ran. Measured steps append a sample to each configuration that ran.
far::Result<void> RunStep(const StudyScene& scene, const RunOptions& options, int s,
                          const StepPlan& plan, std::map<uint32_t, int64_t>& triangles_of,
                          std::vector<Live>& configs) {
  const far::FrameUpdate* frame = s == 0 ? nullptr : &scene.scene.frames[s - 1];
  if (frame != nullptr) TrackTriangles(*frame, triangles_of);
  const bool reference_runs = plan.has_reference && plan.reference_steps.count(s) > 0;
  std::vector<Sample> samples(configs.size());
  std::vector<bool> ran(configs.size(), false);
  for (size_t i : StepOrder(configs.size(), s)) {
    // Occlusion queries may be limited to the first oq_steps measured steps, the reference to
    // its steps; their pipelines still get every update (untimed) so that they stay on the
    // same scene.
    const bool oq = configs[i].spec.mechanism == far::QueryMechanism::kOcclusionQuery;
    const bool run = configs[i].reference ? reference_runs
                                          : !oq || options.oq_steps <= 0 || s <= options.oq_steps;
    auto done = RunOne(configs[i], frame, run, plan.distance, triangles_of, samples[i]);
    if (!done.ok()) {
      return far::MakeError(done.error().code, configs[i].spec.Name() + " at step " +
                                                   std::to_string(s) + ": " + done.error().message);
    }
    ran[i] = *done;
  }
  if (s == 0) return {};
  for (size_t i = 0; i < configs.size(); ++i) {
    if (!ran[i]) continue;
    if (reference_runs) Compare(configs.back(), configs[i], samples[i]);
    samples[i].step = s;
    configs[i].samples.push_back(std::move(samples[i]));
  }
  return {};
}

SceneReport MakeReport(const StudyScene& scene, const std::vector<Live>& configs,
                       const StepPlan& plan) {
  SceneReport report;
  report.name = scene.name;
  report.description = scene.description;
  report.break_note = scene.break_note;
  report.break_step = scene.break_step;
  report.family = scene.family;
  report.kind = scene.kind;
  report.triangles = scene.triangles;
  report.objects = static_cast<int>(scene.scene.objects.size());
  report.steps = static_cast<int>(scene.scene.frames.size());
  report.distance = plan.distance;
  report.checked = plan.has_reference;
  if (plan.has_reference)
    report.reference_steps.assign(plan.reference_steps.begin(), plan.reference_steps.end());
  for (const Live& config : configs) report.rows.push_back(Summarize(config));
  return report;
}

std::string StepList(const std::vector<int>& steps) {
  std::string text;
  for (int s : steps) text += (text.empty() ? "" : ", ") + std::to_string(s);
  return text;
}

}  // namespace

std::vector<int> ReferenceSteps(int steps, int count, const std::vector<int>& key_steps) {
  std::set<int> chosen;
  if (count <= 0 || count >= steps) {
    for (int s = 1; s <= steps; ++s) chosen.insert(s);
  } else {
    for (int i = 0; i < count; ++i) {
      const double at = count == 1 ? 0.0 : static_cast<double>(i) * (steps - 1) / (count - 1);
      chosen.insert(1 + static_cast<int>(at + 0.5));
    }
    for (int s : key_steps) {
      if (s >= 1 && s <= steps) chosen.insert(s);
    }
  }
  return {chosen.begin(), chosen.end()};
}

std::vector<size_t> StepOrder(size_t count, int s) {
  if (count == 0) return {};
  std::vector<size_t> strides;
  for (size_t k = 1; k < std::max<size_t>(count, 2); ++k) {
    if (std::gcd(k, count) == 1) strides.push_back(k);
  }
  // Stride k + 1 with offset k at step k + 1 would keep the last configuration last whenever
  // count is prime (offset - stride = count - 1); stride k pairs with offset k instead.
  const size_t step = static_cast<size_t>(std::max(s, 1));
  const size_t stride = strides[(step - 1) % strides.size()];
  const size_t offset = static_cast<size_t>(std::max(s, 0)) % count;
  std::vector<size_t> order;
  for (size_t n = 0; n < count; ++n) order.push_back((offset + n * stride) % count);
  return order;
}

std::string SceneReport::ReferenceText() const {
  if (!checked) {
    return "no reference (above --scaling-reference-max): missed and false positives not "
           "checked";
  }
  if (static_cast<int>(reference_steps.size()) == steps)
    return "the brute force (`exact`) on every measured step (" + std::to_string(steps) + ")";
  return "the brute force (`exact`) on measured steps " + StepList(reference_steps) + " of " +
         std::to_string(steps) + " (--reference-steps" +
         (break_note.empty() ? "" : "; the break and the step after it always") +
         "): missed and false positives count those steps only";
}

far::Result<SceneReport> RunScene(const StudyScene& scene, const RunOptions& options) {
  const auto scene_start = Clock::now();
  StepPlan plan;
  const std::vector<ConfigSpec> specs = ConfigsFor(scene, options, &plan.has_reference);
  auto made = MakePipelines(scene, specs, plan.has_reference);
  if (!made.ok()) return made.error();
  std::vector<Live>& configs = *made;
  if (RunsDistance(scene, options)) plan.distance = options.distance_fraction * scene.diagonal;
  const int steps = static_cast<int>(scene.scene.frames.size());
  if (plan.has_reference) {
    for (int s : ReferenceSteps(steps, options.reference_steps, scene.key_steps))
      plan.reference_steps.insert(s);
  }
  std::map<uint32_t, int64_t> triangles_of;
  for (const auto& object : scene.scene.objects)
    triangles_of[object.id] = object.mesh.num_triangles();
  if (configs.empty()) return MakeReport(scene, configs, plan);  // --methods
  // Step 0 (not measured) warms up: renderers, shaders, first piece builds and hierarchies, FCL
  // models, auto's GPU probe.
  for (int s = 0; s <= steps; ++s) {
    const auto step_start = Clock::now();
    auto ok = RunStep(scene, options, s, plan, triangles_of, configs);
    if (!ok.ok()) return ok.error();
    if (s == 0) continue;
    std::printf("  %s step %d/%d: %.1f s", scene.name.c_str(), s, steps,
                MillisecondsSince(step_start) / 1000);
    if (plan.has_reference && plan.reference_steps.count(s) > 0) {
      std::printf(", %zu reference contacts", configs.back().contacts.size());
      if (plan.distance) std::printf(", %zu distance pairs", configs.back().distance_pairs.size());
    } else {
      std::printf(", not checked");
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  SceneReport report = MakeReport(scene, configs, plan);
  report.seconds = MillisecondsSince(scene_start) / 1000;
  return report;
}

const Row* Find(const SceneReport& report, const std::string& config, far::Output output) {
  for (const Row& row : report.rows) {
    if (row.config == config && row.spec.output == output) return &row;
  }
  return nullptr;
}

std::vector<far::SceneUpdate> ToUpdates(const far::FrameUpdate& frame) {
  std::vector<far::SceneUpdate> updates;
  for (uint32_t id : frame.removals) updates.push_back(far::RemoveObject{id});
  for (const auto& object : frame.additions) {
    updates.push_back(far::AddObject{object.id, object.mesh, object.motion, object.X_WO});
  }
  for (const auto& [id, pose] : frame.poses) updates.push_back(far::SetPose{id, pose});
  for (const auto& [id, mesh] : frame.vertices) updates.push_back(far::SetVertices{id, mesh.p_MV});
  return updates;
}

}  // namespace far_study
