#include "far/pipeline/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <string>
#include <thread>

#include "gpu_probe.h"
#include "step_runner.h"

#include "far/base/thread_pool.h"
#include "far/gpu/gl_lock.h"
#include "far/pipeline/internal/auto_selector.h"

namespace far {

struct Pipeline::Impl {
  PipelineOptions options;
  std::unique_ptr<GlContext> gl;  // owned context, unless the caller's current one is used
  std::string renderer_name = "none";
  ThreadPool pool;
  SceneModel model;
  internal::StepWorld world;
  std::optional<internal::AutoSelector> selector;  // made on the first auto step
  double cpu_share = 0;                            // SetCpuShare; 0: the pool's threads

  explicit Impl(const PipelineOptions& o)
      : options(o),
        pool(CpuPoolThreads(o.num_threads, o.cpu_cores)),
        model(o.scene_limits, o.shared_budget, o.budget_holder),
        world(pool, o.use_gl, o.gl_batch_ms, o.compute_batcher) {}

  Result<void> Apply(std::vector<SceneUpdate> updates,
                     const std::function<std::string(size_t)>& where);
  Result<StepResult> Step(const StepRequest& request, const StepControl& control);
  Result<StepResult> StepAuto(const StepRequest& request, const StepControl& control);
};

Result<void> Pipeline::Impl::Apply(std::vector<SceneUpdate> updates,
                                   const std::function<std::string(size_t)>& where) {
  // The model checks the whole batch first; then nothing can fail.
  if (auto ok = model.Apply(updates, where); !ok) return ok;
  for (SceneUpdate& update : updates) world.Apply(std::move(update));
  return {};
}

// An auto step: the selector chooses a configuration, the step runs it and its time is
// recorded (auto_selector.h says how it chooses).
Result<StepResult> Pipeline::Impl::StepAuto(const StepRequest& request,
                                            const StepControl& control) {
  if (!selector) {
    selector.emplace(
        world.gpu != nullptr, [] { return internal::ProbeGpuCost(); }, pool.num_threads());
  }
  const internal::SceneSize size{world.cache.size(), model.num_triangles(),
                                 world.cache.structure()};
  std::string reason;
  // A step that calibrates (the GPU probe, a try of a candidate) is setup: the steps after it
  // run the configuration chosen.
  SetupScope setup(&control);
  const internal::Candidate chosen = selector->Choose(size, &reason);
  if (!selector->trying()) setup.End();
  StepRequest concrete = request;
  concrete.method = chosen.method;
  if (chosen.gpu()) {
    concrete.mechanism = chosen.mechanism;
    concrete.resolution = chosen.resolution;
  }
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = pool.WorkersCpuMs() + ThreadPool::CallingThreadCpuMs();
  auto result = Step(concrete, control);
  // A GPU configuration that cannot run this scene (a hierarchy too deep for the kernels' stack,
  // over their 32-bit counts or read-back limit, a GL error) is not a failed step for auto: it
  // is left out from now on, and bvh answers.
  const bool gpu_refused = !result && (chosen.gpu() || chosen.method == Method::kGpu) &&
                           (result.error().code == ErrorCode::kUnavailable ||
                            result.error().code == ErrorCode::kLimitExceeded ||
                            result.error().code == ErrorCode::kInternal);
  if (gpu_refused) {
    selector->Exclude(chosen);
    reason += "; " + chosen.Name() + " failed and is left out (" + result.error().message + ")";
    concrete.method = Method::kBvh;
    result = Step(concrete, control);
  }
  if (!result) return result;
  if (!gpu_refused) {
    const double cpu_ms = pool.WorkersCpuMs() + ThreadPool::CallingThreadCpuMs() - cpu_start;
    selector->set_cpu_share(cpu_share > 0 ? cpu_share : pool.num_threads());
    selector->Record(
        chosen,
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count(),
        cpu_ms);
  }
  result->stats.method_reason = std::move(reason);
  return result;
}

// One step: a checked request, auto's choice, then the stages (step_runner.h).
Result<StepResult> Pipeline::Impl::Step(const StepRequest& request, const StepControl& control) {
  if (auto ok = CheckStepRequest(request); !ok) return ok.error();
  if (request.method == Method::kAuto) return StepAuto(request, control);
  if (NeedsGl(request.method) && !world.gpu) {
    return MakeError(ErrorCode::kUnavailable, "method '" + std::string(ToString(request.method)) +
                                                  "' needs the GPU, and this pipeline has no GL "
                                                  "context");
  }
  return internal::RunStep(world, request, control);
}

int CpuPoolThreads(int num_threads, int cpu_cores) {
  if (num_threads > 0 && cpu_cores > 0) return std::min(num_threads, cpu_cores);
  if (num_threads > 0 || cpu_cores > 0) return std::max(num_threads, cpu_cores);
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

Pipeline::Pipeline(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Pipeline::~Pipeline() = default;

Result<std::unique_ptr<Pipeline>> Pipeline::Create(const PipelineOptions& options) {
  auto impl = std::make_unique<Impl>(options);
  if (options.use_gl && !options.use_current_context) {
    auto gl = GlContext::Create(options.platform, options.gpu_device);
    if (!gl.ok()) return gl.error();
    impl->gl = std::move(*gl);
    impl->renderer_name = impl->gl->renderer();
  } else if (options.use_gl) {
    const auto gl = LockGl();
    impl->renderer_name = internal::CurrentGlRenderer();
    if (impl->renderer_name.empty()) {
      return MakeError(ErrorCode::kUnavailable,
                       "use_current_context: no GL context is current on this thread");
    }
  }
  return std::unique_ptr<Pipeline>(new Pipeline(std::move(impl)));
}

Result<void> Pipeline::Apply(std::vector<SceneUpdate> updates,
                             const std::function<std::string(size_t)>& where) {
  return impl_->Apply(std::move(updates), where);
}

namespace {
// Single updates report the model's error as it is, without an update number.
std::string NoPrefix(size_t) { return ""; }
}  // namespace

Result<void> Pipeline::AddObject(uint32_t id, Mesh mesh, Motion motion, const Pose& X_WO) {
  return Apply({far::AddObject{id, std::move(mesh), motion, X_WO}}, NoPrefix);
}
Result<void> Pipeline::RemoveObject(uint32_t id) {
  return Apply({far::RemoveObject{id}}, NoPrefix);
}
Result<void> Pipeline::SetPose(uint32_t id, const Pose& X_WO) {
  return Apply({far::SetPose{id, X_WO}}, NoPrefix);
}
Result<void> Pipeline::SetVertices(uint32_t id, std::vector<Eigen::Vector3d> p_MV) {
  return Apply({far::SetVertices{id, std::move(p_MV)}}, NoPrefix);
}

Result<void> Pipeline::LoadScene(const Scene& scene) {
  std::vector<SceneUpdate> updates;
  for (const SceneObject& object : scene.objects) {
    updates.push_back(far::AddObject{object.id, object.mesh, object.motion, object.X_WO});
  }
  return Apply(std::move(updates), [&](size_t i) { return "objects[" + std::to_string(i) + "]."; });
}

std::optional<GpuCost> MeasureGpuCost() { return internal::ProbeGpuCost(); }

bool UseGpuCost(const GpuCost& cost) { return internal::AdoptGpuCost(cost); }

Result<StepResult> Pipeline::Step(const StepRequest& request, const StepControl& control) {
  return impl_->Step(request, control);
}
int Pipeline::num_objects() const { return impl_->world.cache.size(); }
int64_t Pipeline::num_triangles() const { return impl_->model.num_triangles(); }
void Pipeline::SetCpuBackground(int max_threads) { impl_->pool.SetBackground(max_threads); }
void Pipeline::SetCpuShare(double cores) {
  impl_->cpu_share = cores;
  impl_->pool.SetShare(cores > 0 ? static_cast<int>(std::floor(cores + 1e-9))
                                 : impl_->pool.num_threads());
}
int Pipeline::cpu_threads() const { return impl_->pool.num_threads(); }
const SceneCounters& Pipeline::counters() const { return impl_->world.cache.counters(); }
std::string Pipeline::gl_renderer() const { return impl_->renderer_name; }

}  // namespace far
