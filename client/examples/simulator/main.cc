// A minimal simulator: one falling box over a static floor, stepped through far-daemon.
//   cmake -S . -B build -DCMAKE_PREFIX_PATH=<far install prefix> && cmake --build build
//   ./build/simulator            (far-daemon on its default socket; docs/daemon.md)
//   ./build/simulator SOCKET     (far-daemon --socket SOCKET)
#include <cstdio>

#include "far/client/client.h"

namespace {

// An axis-aligned box as 12 triangles.
far::Mesh Box(const Eigen::Vector3d& half) {
  far::Mesh mesh;
  for (int k = 0; k < 8; ++k) {
    mesh.p_MV.emplace_back((k & 1) ? half.x() : -half.x(), (k & 2) ? half.y() : -half.y(),
                           (k & 4) ? half.z() : -half.z());
  }
  mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                    {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return mesh;
}

}  // namespace

int main(int argc, char** argv) {
  far::client::ClientOptions options;
  options.client_name = "example-simulator";
  if (argc > 1) options.socket_path = argv[1];
  auto client = far::client::Client::Connect(options);
  if (!client) {
    std::fprintf(stderr, "%s\n", far::ToString(client.error()).c_str());
    return 1;
  }
  far::Pose floor_pose, box_pose;
  (void)(*client)->AddObject(1, Box({5, 5, 0.1}), far::Motion::kStatic, floor_pose);
  box_pose.translation = {0, 0, 1.0};
  (void)(*client)->AddObject(2, Box({0.5, 0.5, 0.5}), far::Motion::kRigid, box_pose);
  far::StepRequest request;
  request.resolution = 256;
  for (int step = 0; step < 10; ++step) {
    box_pose.translation.z() -= 0.06;  // the simulator's own dynamics
    if (auto ok = (*client)->SetPose(2, box_pose); !ok) return 1;
    auto result = (*client)->Step(request);
    if (!result) {
      std::fprintf(stderr, "%s\n", far::ToString(result.error()).c_str());
      return 1;
    }
    std::printf("step %d: box at z=%.2f, %zu contact pairs\n", step, box_pose.translation.z(),
                result->contacts.size());
  }
  return 0;
}
