// far._pipeline: far.Pipeline, the step pipeline in this process (far::Pipeline), for a
// simulator that wants no daemon. Links GL and EGL: far/__init__.py imports it only when
// far.Pipeline is first used.
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>

#include "arrays.h"
#include "errors.h"
#include "pose.h"
#include "request.h"
#include "result.h"
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "far/io/scene_io.h"
#include "far/pipeline/pipeline.h"

namespace py = pybind11;

namespace far::python {
namespace {

// A far::Pipeline and the thread that made it. The pipeline's GL context is current on that
// thread only (pipeline.h), so every call checks it: far.WrongThreadError, not a crash in the
// driver. The GIL is released while a step runs (same thread: other Python threads run).
class PyPipeline {
 public:
  explicit PyPipeline(const PipelineOptions& options) : owner_(std::this_thread::get_id()) {
    Result<std::unique_ptr<Pipeline>> made = [&] {
      py::gil_scoped_release release;
      return Pipeline::Create(options);
    }();
    pipeline_ = Unwrap(std::move(made));
  }

  // Freed on another thread (the last reference dropped there), the GL context cannot be
  // destroyed there: the pipeline is leaked instead of crashing in the driver.
  ~PyPipeline() {
    if (std::this_thread::get_id() != owner_) (void)pipeline_.release();
  }
  PyPipeline(const PyPipeline&) = delete;
  PyPipeline& operator=(const PyPipeline&) = delete;

  Pipeline& Get() {
    if (std::this_thread::get_id() != owner_) {
      std::ostringstream message;
      message << "far.Pipeline: called from thread " << std::this_thread::get_id()
              << ", made on thread " << owner_
              << "; a Pipeline is used only on the thread that made it (its GL context is "
                 "current there); make one per thread";
      ThrowNamed("WrongThreadError", message.str());
    }
    return *pipeline_;
  }

  void AddObject(uint32_t id, const py::handle& vertices, const py::handle& triangles,
                 const std::string& motion, const py::handle& translation,
                 const py::handle& rotation_wxyz) {
    Pipeline& pipeline = Get();
    Mesh mesh;
    const auto p_MV = Vector3Span(vertices, "vertices");
    mesh.p_MV.assign(p_MV.begin(), p_MV.end());
    mesh.triangles = Triangles(triangles, "triangles");
    Check(pipeline.AddObject(id, std::move(mesh), ToMotion(motion),
                             ToPose(translation, rotation_wxyz)));
  }

  void SetVertices(uint32_t id, const py::handle& vertices) {
    Pipeline& pipeline = Get();
    // One copy: far::Pipeline takes the positions as a vector it keeps (the scene owns them).
    const auto p_MV = Vector3Span(vertices, "vertices");
    Check(pipeline.SetVertices(id, std::vector<Eigen::Vector3d>(p_MV.begin(), p_MV.end())));
  }

  py::object Step(const StepRequest& request) {
    Pipeline& pipeline = Get();
    Result<StepResult> result = [&] {
      py::gil_scoped_release release;
      return pipeline.Step(request);
    }();
    return ToPython(Unwrap(std::move(result)));
  }

  void LoadScene(const std::string& path) {
    Pipeline& pipeline = Get();
    Result<Scene> scene = [&] {
      py::gil_scoped_release release;
      return ReadScene(path);
    }();
    Check(pipeline.LoadScene(Unwrap(std::move(scene))));
  }

 private:
  std::thread::id owner_;
  std::unique_ptr<Pipeline> pipeline_;
};

PipelineOptions ToPipelineOptions(const std::string& platform, int gpu_device, int num_threads,
                                  int cpu_cores, bool use_gl) {
  PipelineOptions options;
  auto p = ParseGlPlatform(platform);
  if (!p) {
    ThrowArgument("platform",
                  "unknown '" + platform + "'; the platforms are: " + GlPlatformNames());
  }
  if (num_threads < 0) ThrowArgument("num_threads", "must be >= 0 (0: every core)");
  if (cpu_cores < 0) ThrowArgument("cpu_cores", "must be >= 0 (0: every core)");
  options.platform = *p;
  options.gpu_device = gpu_device;
  options.num_threads = num_threads;
  options.cpu_cores = cpu_cores;
  options.use_gl = use_gl;
  return options;
}

}  // namespace
}  // namespace far::python

PYBIND11_MODULE(_pipeline, m) {
  using namespace far::python;
  m.doc() = "far.Pipeline: the step pipeline in this process (docs/python.md)";

  py::class_<PyPipeline>(m, "Pipeline", R"doc(
The FAR step pipeline in this process (far::Pipeline): one scene, a GL context (unless
use_gl=False: CPU methods only) and a CPU pool. The same object, pose, vertex and step API as
far.Client. Use it only on the thread that made it (far.WrongThreadError otherwise).)doc")
      .def(py::init([](const std::string& platform, int gpu_device, int num_threads, int cpu_cores,
                       bool use_gl) {
             return std::make_unique<PyPipeline>(
                 ToPipelineOptions(platform, gpu_device, num_threads, cpu_cores, use_gl));
           }),
           py::kw_only(), py::arg("platform") = "auto", py::arg("gpu_device") = -1,
           py::arg("num_threads") = 0, py::arg("cpu_cores") = 0, py::arg("use_gl") = true)
      .def("add_object", &PyPipeline::AddObject, py::arg("id"), py::arg("vertices"),
           py::arg("triangles"), py::kw_only(), py::arg("motion") = "rigid",
           py::arg("translation") = py::make_tuple(0.0, 0.0, 0.0),
           py::arg("rotation_wxyz") = py::make_tuple(1.0, 0.0, 0.0, 0.0))
      .def(
          "remove_object",
          [](PyPipeline& self, uint32_t id) { Check(self.Get().RemoveObject(id)); }, py::arg("id"))
      .def(
          "set_pose",
          [](PyPipeline& self, uint32_t id, const py::handle& translation,
             const py::handle& rotation_wxyz) {
            far::Pipeline& pipeline = self.Get();
            Check(pipeline.SetPose(id, ToPose(translation, rotation_wxyz)));
          },
          py::arg("id"), py::arg("translation"),
          py::arg("rotation_wxyz") = py::make_tuple(1.0, 0.0, 0.0, 0.0))
      .def("set_vertices", &PyPipeline::SetVertices, py::arg("id"), py::arg("vertices"))
      .def("load_scene", &PyPipeline::LoadScene, py::arg("path"))
      .def(
          "step",
          [](PyPipeline& self, const std::string& method, const std::string& mechanism,
             int resolution, const std::string& depth_format, int subobject_size,
             std::optional<double> distance, std::optional<std::string> output, bool geometry) {
            return self.Step(ToStepRequest(method, mechanism, resolution, depth_format,
                                           subobject_size, distance, output, geometry));
          },
          FAR_PYTHON_STEP_ARGS)
      .def_property_readonly("num_objects",
                             [](PyPipeline& self) { return self.Get().num_objects(); })
      .def_property_readonly("num_triangles",
                             [](PyPipeline& self) { return self.Get().num_triangles(); })
      .def_property_readonly("cpu_threads",
                             [](PyPipeline& self) { return self.Get().cpu_threads(); })
      .def_property_readonly("gl_renderer",
                             [](PyPipeline& self) { return self.Get().gl_renderer(); });
}
