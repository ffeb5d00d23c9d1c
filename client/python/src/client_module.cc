// far._client: far.Client, a session with far-daemon (far::client::Client). Links no GL, EGL or
// FCL, like far-client: a simulator that only talks to a daemon loads none of them.
#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "arrays.h"
#include "errors.h"
#include "pose.h"
#include "request.h"
#include "result.h"
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "far/client/client.h"
#include "far/io/scene_io.h"
#include "far/model/version.h"

namespace py = pybind11;

namespace far::python {
namespace {

// A duration argument: seconds (an int or a float) or a datetime.timedelta; >= 0.
std::chrono::milliseconds ToMilliseconds(const py::handle& value, const char* argument) {
  double seconds = -1;
  if (py::hasattr(value, "total_seconds")) {
    seconds = value.attr("total_seconds")().cast<double>();
  } else if ((py::isinstance<py::float_>(value) || py::isinstance<py::int_>(value)) &&
             !py::isinstance<py::bool_>(value)) {
    seconds = value.cast<double>();
  } else {
    ThrowArgument(argument, "expected seconds (a number) or a datetime.timedelta, got " +
                                std::string(py::str(py::repr(value))));
  }
  if (!(seconds >= 0) || seconds > 1e9)
    ThrowArgument(argument,
                  "expected a duration of 0 seconds or more, got " + FormatDouble(seconds));
  return std::chrono::milliseconds(static_cast<int64_t>(seconds * 1000 + 0.5));
}
using client::Client;
using client::ClientOptions;

ClientOptions ToOptions(const std::string& daemon, const std::string& socket_path,
                        const std::string& lcm_url, const std::string& client_name,
                        const py::handle& connect_timeout, const py::handle& hear_timeout,
                        const py::handle& timeout, std::optional<std::string> record_path) {
  auto ms = [](const char* argument, const py::handle& s) { return ToMilliseconds(s, argument); };
  ClientOptions options;
  options.daemon = daemon;
  options.socket_path = socket_path;
  options.lcm_url = lcm_url;
  options.client_name = client_name;
  options.connect_timeout = ms("connect_timeout", connect_timeout);
  options.hear_timeout = ms("hear_timeout", hear_timeout);
  options.timeout = ms("timeout", timeout);
  options.record_path = std::move(record_path);
  return options;
}

// The options of far::client::ClientOptions, by the same names; durations in seconds (a float
// or a datetime.timedelta).
#define FAR_PYTHON_CLIENT_OPTIONS                                                 \
  py::kw_only(), py::arg("daemon") = std::string(), py::arg("socket_path") = "",  \
                 py::arg("lcm_url") = "", py::arg("client_name") = "far-python",  \
                 py::arg("connect_timeout") = 1.0, py::arg("hear_timeout") = 1.0, \
                 py::arg("timeout") = 60.0, py::arg("record_path") = py::none()

// One far::client::Client. Every call of it is thread-safe (client.h), so Python threads may
// share a far.Client without a lock of ours. Every call runs with the GIL released (an update
// may wait for room in the ring), so other threads run Python meanwhile. (Keeping the GIL over
// a pose's ring write measured no faster in the step benchmark, bench/RESULTS.md.)
class PyClient {
 public:
  explicit PyClient(const ClientOptions& options) {
    Result<std::unique_ptr<Client>> connected = [&] {
      py::gil_scoped_release release;
      return Client::Connect(options);
    }();
    client_ = Unwrap(std::move(connected));
  }

  // Runs `call` on the client with the GIL released.
  template <typename Call>
  auto Released(Call&& call) {
    py::gil_scoped_release release;
    return call(*client_);
  }

  void AddObject(uint32_t id, const py::handle& vertices, const py::handle& triangles,
                 const std::string& motion, const py::handle& translation,
                 const py::handle& rotation_wxyz) {
    Mesh mesh;
    const auto p_MV = Vector3Span(vertices, "vertices");
    mesh.p_MV.assign(p_MV.begin(), p_MV.end());
    mesh.triangles = Triangles(triangles, "triangles");
    const Motion m = ToMotion(motion);
    const Pose pose = ToPose(translation, rotation_wxyz);
    Check(Released([&](Client& c) { return c.AddObject(id, mesh, m, pose); }));
  }

  void SetVertices(uint32_t id, const py::handle& vertices) {
    // No copy: the span is the array's memory, read straight into the shared-memory ring.
    // `vertices` (a reference held by this call's arguments) outlives the call.
    const auto p_MV = Vector3Span(vertices, "vertices");
    Check(Released([&](Client& c) { return c.SetVertices(id, p_MV); }));
  }

  py::object Step(const StepRequest& request) {
    Result<StepResult> result = Released([&](Client& c) { return c.Step(request); });
    return ToPython(Unwrap(std::move(result)));
  }

  void LoadScene(const std::string& path) {
    Result<Scene> scene = [&] {
      py::gil_scoped_release release;
      return ReadScene(path);
    }();
    const Scene loaded = Unwrap(std::move(scene));
    Check(Released([&](Client& c) { return c.LoadScene(loaded); }));
  }

  Client& client() { return *client_; }

 private:
  std::unique_ptr<Client> client_;
};

py::dict StatusDict(const client::DaemonStatus& s) {
  py::list sessions;
  for (const auto& session : s.sessions) {
    sessions.append(py::dict(
        py::arg("id") = session.id, py::arg("uid") = session.uid, py::arg("pid") = session.pid,
        py::arg("client_name") = session.client_name, py::arg("steps") = session.steps,
        py::arg("objects") = session.objects, py::arg("triangles") = session.triangles,
        py::arg("latency_p50_ms") = session.latency_p50_ms,
        py::arg("latency_p99_ms") = session.latency_p99_ms));
  }
  py::dict errors, methods;
  for (const auto& [kind, count] : s.errors_by_kind) errors[py::str(kind)] = count;
  for (const auto& [method, steps] : s.steps_by_method) methods[py::str(method)] = steps;
  py::dict out;
  out["daemon_version"] = s.daemon_version;
  out["daemon_name"] = s.daemon_name;
  out["gl_renderer"] = s.gl_renderer;
  out["gl_device"] = s.gl_device;
  out["lcm_url"] = s.lcm_url;
  out["channel_prefix"] = s.channel_prefix;
  out["socket_path"] = s.socket_path;
  out["uptime_ms"] = s.uptime_ms;
  out["steps_total"] = s.steps_total;
  out["errors_total"] = s.errors_total;
  out["rejected_messages_total"] = s.rejected_messages_total;
  out["max_sessions"] = s.max_sessions;
  out["max_sessions_per_user"] = s.max_sessions_per_user;
  out["sessions_open"] = s.sessions_open;
  out["latency_p50_ms"] = s.latency_p50_ms;
  out["latency_p90_ms"] = s.latency_p90_ms;
  out["latency_p99_ms"] = s.latency_p99_ms;
  out["latency_max_ms"] = s.latency_max_ms;
  out["latency_samples"] = s.latency_samples;
  out["sessions"] = sessions;
  out["errors_by_kind"] = errors;
  out["daemon_pid"] = s.daemon_pid;
  out["gpu_names"] = s.gpu_names;
  out["opens_refused_total"] = s.opens_refused_total;
  out["memory_rss_bytes"] = s.memory_rss_bytes;
  out["segment_bytes"] = s.segment_bytes;
  out["steps_by_method"] = methods;
  return out;
}

// Client.status: the daemon's status as a dict, asked with the GIL released.
py::dict Status(const std::string& daemon, const std::string& socket_path,
                const std::string& lcm_url, const std::string& client_name,
                const py::handle& connect_timeout, const py::handle& hear_timeout,
                const py::handle& timeout, std::optional<std::string> record_path) {
  const auto options = ToOptions(daemon, socket_path, lcm_url, client_name, connect_timeout,
                                 hear_timeout, timeout, record_path);
  far::Result<far::client::DaemonStatus> status = [&] {
    py::gil_scoped_release release;
    return far::client::Client::Status(options);
  }();
  return StatusDict(Unwrap(std::move(status)));
}

// For tests (tests/python): the address set_vertices would read `vertices` from, to show that
// the array's own memory is what the C++ side sees.
std::uintptr_t Vector3SpanAddress(const py::handle& vertices) {
  return reinterpret_cast<std::uintptr_t>(Vector3Span(vertices, "vertices").data());
}

}  // namespace
}  // namespace far::python

PYBIND11_MODULE(_client, m) {
  using namespace far::python;
  using far::client::Client;
  m.doc() = "far.Client: a session with far-daemon (docs/python.md)";
  m.attr("__version__") = far::kVersion;

  py::class_<PyClient>(m, "Client", R"doc(
A session with far-daemon (far::client::Client): opened by the constructor, closed by close(),
by `with`, or when the object goes away. Updates take effect at the next step().

Keyword arguments are far::client::ClientOptions': daemon, socket_path, lcm_url, client_name,
connect_timeout, hear_timeout, timeout (seconds or datetime.timedelta), record_path.
Every wait (connect, step, close, status) runs with the GIL released. Errors: far.Error.)doc")
      .def(py::init([](const std::string& daemon, const std::string& socket_path,
                       const std::string& lcm_url, const std::string& client_name,
                       const py::handle& connect_timeout, const py::handle& hear_timeout,
                       const py::handle& timeout, std::optional<std::string> record_path) {
             return std::make_unique<PyClient>(ToOptions(daemon, socket_path, lcm_url, client_name,
                                                         connect_timeout, hear_timeout, timeout,
                                                         record_path));
           }),
           FAR_PYTHON_CLIENT_OPTIONS)
      .def("add_object", &PyClient::AddObject, py::arg("id"), py::arg("vertices"),
           py::arg("triangles"), py::kw_only(), py::arg("motion") = "rigid",
           py::arg("translation") = py::make_tuple(0.0, 0.0, 0.0),
           py::arg("rotation_wxyz") = py::make_tuple(1.0, 0.0, 0.0, 0.0),
           "Adds object `id`: vertices (N, 3) float64 in its own frame, triangles (M, 3) uint32, "
           "motion 'static', 'rigid' or 'deformable', and its pose.")
      .def(
          "remove_object",
          [](PyClient& self, uint32_t id) { Check(self.client().RemoveObject(id)); }, py::arg("id"))
      .def(
          "set_pose",
          [](PyClient& self, uint32_t id, const py::handle& translation,
             const py::handle& rotation_wxyz) {
            const far::Pose pose = ToPose(translation, rotation_wxyz);
            Check(self.Released([&](Client& c) { return c.SetPose(id, pose); }));
          },
          py::arg("id"), py::arg("translation"),
          py::arg("rotation_wxyz") = py::make_tuple(1.0, 0.0, 0.0, 0.0))
      .def("set_vertices", &PyClient::SetVertices, py::arg("id"), py::arg("vertices"),
           "New vertex positions of a deformable object: a C-contiguous float64 (N, 3) array, "
           "read in place (no copy).")
      .def("load_scene", &PyClient::LoadScene, py::arg("path"),
           "Adds every object of a far-scene/1 file (docs/scene-format.md).")
      .def(
          "step",
          [](PyClient& self, const std::string& method, const std::string& mechanism,
             int resolution, const std::string& depth_format, int subobject_size,
             std::optional<double> distance, std::optional<std::string> output, bool geometry) {
            return self.Step(ToStepRequest(method, mechanism, resolution, depth_format,
                                           subobject_size, distance, output, geometry));
          },
          FAR_PYTHON_STEP_ARGS,
          "Runs one step and waits for the reply (GIL released): a far.StepResult. The "
          "options are far-client collide's.")
      .def("close",
           [](PyClient& self) { Check(self.Released([](Client& c) { return c.Close(); })); })
      .def_property_readonly("session_id",
                             [](PyClient& self) { return self.client().session_id(); })
      .def_property_readonly("recording_path",
                             [](PyClient& self) { return self.client().recording_path(); })
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__",
           [](PyClient& self, const py::args&) {
             // Close errors (the daemon already gone) do not hide the block's own exception.
             (void)self.Released([](Client& c) { return c.Close(); });
           })
      .def_static("status", &Status, FAR_PYTHON_CLIENT_OPTIONS,
                  "The daemon's status (far-client status --json) as a dict; GIL released.");

  m.def("_vector3_span_address", &Vector3SpanAddress, py::arg("vertices"));
}
