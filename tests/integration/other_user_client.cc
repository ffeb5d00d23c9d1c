#include "other_user_client.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <thread>
#include <vector>

#include "integration_scenes.h"
#include "raw_session.h"

#include "far/client/client.h"

namespace far::integration {
namespace {

int Fail(const std::string& what, const Error& error) {
  std::printf("error %s: %s\n", what.c_str(), far::ToString(error).c_str());
  std::fflush(stdout);
  return 2;
}

// The cheapest step: the daemon applies the session's updates and answers with the object PCS.
StepRequest DrainRequest() {
  StepRequest request;
  request.method = Method::kAabb;
  request.output = Output::kObjectPcs;
  return request;
}

}  // namespace

int OtherUserClientMain(const std::string& socket) {
  client::ClientOptions options;
  options.socket_path = socket;
  options.client_name = kOtherUserClientName;
  options.timeout = std::chrono::seconds(10);
  auto client = client::Client::Connect(options);
  if (!client) return Fail("connect", client.error());
  Scene scene;
  scene.objects = ContactSoup(kHealthySeed);
  if (auto loaded = (*client)->LoadScene(scene); !loaded) return Fail("load", loaded.error());
  auto result = (*client)->Step(SmallRequest());
  if (!result) return Fail("step", result.error());
  std::printf("stepped %d %zu\n", static_cast<int>(getuid()), result->contacts.size());
  auto status = client::Client::Status(options);
  if (!status) return Fail("status", status.error());
  for (const auto& session : status->sessions) {
    std::printf("session %d %s %lld\n", session.uid, session.client_name.c_str(),
                static_cast<long long>(session.triangles));
  }
  std::printf("end %d\n", status->sessions_open);
  std::fflush(stdout);
  // The test asks for root's view of the sessions while this one is still open.
  std::this_thread::sleep_for(std::chrono::seconds(60));
  return 0;
}

int HoldingClientMain(const std::string& socket, int sessions, int64_t triangles,
                      const std::string& go) {
  Mesh mesh;
  mesh.p_MV = {Eigen::Vector3d::Zero()};
  mesh.triangles.assign(static_cast<size_t>(std::max<int64_t>(triangles, 0)), {0, 0, 0});
  std::vector<std::unique_ptr<client::Client>> held;
  for (int i = 0; i < sessions; ++i) {
    client::ClientOptions options;
    options.socket_path = socket;
    options.client_name = "holder-" + std::to_string(i);
    options.timeout = std::chrono::seconds(20);
    auto client = client::Client::Connect(options);
    if (!client) return Fail("connect " + std::to_string(i), client.error());
    if (triangles > 0) {
      if (auto added = (*client)->AddObject(1, mesh, Motion::kStatic); !added)
        return Fail("add " + std::to_string(i), added.error());
      if (auto stepped = (*client)->Step(DrainRequest()); !stepped)
        return Fail("step " + std::to_string(i), stepped.error());
    }
    held.push_back(std::move(*client));
  }
  std::printf("held %d %lld\n", sessions, static_cast<long long>(sessions * triangles));
  std::fflush(stdout);
  // Idle until the test says so.
  for (int waited_ms = 0; waited_ms < 60'000 && !std::filesystem::exists(go); waited_ms += 20)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  for (size_t i = 0; i < held.size(); ++i) {
    auto stepped = held[i]->Step(DrainRequest());
    if (stepped) {
      std::printf("session %zu ok\n", i);
    } else {
      std::printf("session %zu error %s\n", i, far::ToString(stepped.error()).c_str());
    }
  }
  std::printf("end\n");
  std::fflush(stdout);
  return 0;
}

}  // namespace far::integration
