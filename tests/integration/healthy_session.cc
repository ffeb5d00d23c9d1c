#include "healthy_session.h"

#include "daemon_process.h"
#include "integration_scenes.h"
#include "raw_session.h"

namespace far::integration {

std::unique_ptr<client::Client> HealthySession(const std::string& name) {
  auto client = client::Client::Connect(TestClientOptions(name));
  EXPECT_TRUE(client.ok()) << name << ": " << far::ToString(client.error());
  if (!client) return nullptr;
  Scene scene;
  scene.objects = ContactSoup(kHealthySeed);
  EXPECT_TRUE((*client)->LoadScene(scene).ok());
  auto result = (*client)->Step(SmallRequest());
  EXPECT_TRUE(result.ok()) << name << ": " << far::ToString(result.error());
  if (!result) return nullptr;
  EXPECT_EQ(result->contacts, ReferenceContacts(scene.objects)) << name;
  return std::move(*client);
}

::testing::AssertionResult StepsWithTheReference(client::Client& client) {
  static const auto kExpected = ReferenceContacts(ContactSoup(kHealthySeed));
  auto result = client.Step(SmallRequest());
  if (!result) return ::testing::AssertionFailure() << far::ToString(result.error());
  if (result->contacts != kExpected)
    return ::testing::AssertionFailure() << "contacts " << ToString(result->contacts);
  return ::testing::AssertionSuccess();
}

int SessionsOpen() {
  auto status = client::Client::Status(TestClientOptions("status"));
  return status ? status->sessions_open : -1;
}

}  // namespace far::integration
