// The C++ side of client/python/bench/step_benchmark.py: a far::client session that loads the
// benchmark's scene and, for each line "steps <k>" on stdin, runs k simulator steps (a pose for
// every rigid object, then a step) exactly as the Python side does, printing the wall time of
// each in microseconds on one line. Interleaving the two clients' rounds in one run puts both
// under the same daemon, machine load and cache state.
//   far_python_bench_peer <socket> <scene.json>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "far/client/client.h"
#include "far/io/scene_io.h"

namespace {

int Fail(const std::string& what, const far::Error& error) {
  std::fprintf(stderr, "far_python_bench_peer: %s: %s\n", what.c_str(),
               far::ToString(error).c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: far_python_bench_peer <socket> <scene.json>\n");
    return 2;
  }
  auto scene = far::ReadScene(argv[2]);
  if (!scene) return Fail(argv[2], scene.error());
  far::client::ClientOptions options;
  options.socket_path = argv[1];
  options.client_name = "bench-cpp";
  auto connected = far::client::Client::Connect(options);
  if (!connected) return Fail("connect", connected.error());
  far::client::Client& client = **connected;
  if (auto loaded = client.LoadScene(*scene); !loaded) return Fail("load", loaded.error());

  std::vector<const far::SceneObject*> rigid;
  for (const auto& object : scene->objects)
    if (object.motion == far::Motion::kRigid) rigid.push_back(&object);
  const far::StepRequest request;  // auto, contacts: far.Client.step()'s defaults
  long long step = 0;
  std::string command;
  int count = 0;
  std::printf("ready\n");
  std::fflush(stdout);
  while (std::cin >> command >> count) {
    std::string line;
    for (int i = 0; i < count; ++i, ++step) {
      const auto start = std::chrono::steady_clock::now();
      for (const far::SceneObject* object : rigid) {
        far::Pose pose = object->X_WO;
        pose.translation.z() += 0.002 * static_cast<double>(step % 10);
        if (auto set = client.SetPose(object->id, pose); !set) return Fail("set_pose", set.error());
      }
      auto result = client.Step(request);
      if (!result) return Fail("step", result.error());
      const auto us =
          std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start)
              .count();
      line += std::to_string(us) + " " + std::to_string(result->contacts.size()) + " ";
    }
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  }
  return 0;
}
