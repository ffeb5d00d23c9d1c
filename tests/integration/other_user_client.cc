#include "other_user_client.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <thread>

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

}  // namespace far::integration
