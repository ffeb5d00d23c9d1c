// What another local user sees of a session on the bus (docs/protocol.md, "What the design
// protects"): a passive listener on every LCM channel of the daemon's URL, while a client steps
// through a scene with contacts. It must find sealed_t messages only on the reply channel, none
// of them opening with any key but the session's, no inner message in clear, and the client's
// name nowhere.

#include <algorithm>
#include <string>
#include <vector>

#include "daemon_fixture.h"
#include "far_lcm/step_reply_t.hpp"
#include "far_lcm/step_status_t.hpp"
#include "integration_scenes.h"
#include "raw_session.h"
#include <gtest/gtest.h>

#include "far/client/client.h"
#include "far/protocol/channels.h"
#include "far/protocol/message.h"
#include "far/protocol/session_auth.h"

namespace far::integration {
namespace {

using PrivacyTest = DaemonTest;

bool Contains(const std::vector<uint8_t>& bytes, const std::string& text) {
  return std::search(bytes.begin(), bytes.end(), text.begin(), text.end()) != bytes.end();
}

// An int64 as LCM encodes it (big-endian).
std::vector<uint8_t> BigEndian64(int64_t value) {
  std::vector<uint8_t> out;
  for (int shift = 56; shift >= 0; shift -= 8) out.push_back(static_cast<uint8_t>(value >> shift));
  return out;
}

TEST_F(PrivacyTest, APassiveListenerReadsNothingOfAnotherSession) {
  ASSERT_NE(StartDaemon(), nullptr);
  auto listener = Listener::Create(TestLcmUrl());
  ASSERT_TRUE(listener.ok()) << far::ToString(listener.error());
  (*listener)->Subscribe(".*");
  (*listener)->Start();

  const std::string name = "private-simulator-7f3a";
  auto client = client::Client::Connect(TestClientOptions(name));
  ASSERT_TRUE(client.ok()) << far::ToString(client.error());
  const std::vector<SceneObject> objects = ContactSoup(11);
  for (const SceneObject& object : objects)
    ASSERT_TRUE((*client)->AddObject(object.id, object.mesh, object.motion, object.X_WO).ok());
  StepRequest request;
  request.method = Method::kBvh;
  std::vector<ContactPair> contacts;
  for (int step = 0; step < 5; ++step) {
    auto result = (*client)->Step(request);
    ASSERT_TRUE(result.ok()) << far::ToString(result.error());
    contacts = result->contacts;
  }
  ASSERT_FALSE(contacts.empty());
  ASSERT_TRUE(
      WaitUntil([&] { return (*listener)->Snapshot().size() >= 10; }, std::chrono::seconds(5)));

  const std::vector<Received> seen = (*listener)->Snapshot();
  const protocol::SessionKey guess = protocol::NewSessionKey();
  int sealed = 0;
  for (const Received& message : seen) {
    SCOPED_TRACE(message.channel);
    EXPECT_FALSE(Contains(message.bytes, name)) << "the client's name is on the bus";
    if (message.channel == "LCM_SELF_TEST") continue;  // LCM's own, at start-up
    auto type = protocol::IdentifyMessage(message.bytes.data(), message.bytes.size());
    ASSERT_TRUE(type.ok());
    if (message.channel.ends_with("_REQ")) {
      // Requests are MACed, not secret: they say what was asked (method, outputs), not what
      // the scene holds or what touched.
      EXPECT_EQ(*type, protocol::MessageType::kStepRequest);
      continue;
    }
    ASSERT_TRUE(message.channel.ends_with("_REPLY"));
    EXPECT_EQ(*type, protocol::MessageType::kSealed) << protocol::ToString(*type);
    ++sealed;
    // Not with a guessed key, and not as another session.
    EXPECT_FALSE(protocol::OpenSealed(message.bytes.data(), message.bytes.size(),
                                      (*client)->session_id(), guess, 1 << 20)
                     .ok());
    // The box is ciphertext: the inner step_reply_t / step_status_t encoding, which starts
    // with its type's fingerprint, is nowhere in clear (a box that were only authenticated
    // would show it).
    for (int64_t hash : {far_lcm::step_reply_t::getHash(), far_lcm::step_status_t::getHash()}) {
      const std::vector<uint8_t> fingerprint = BigEndian64(hash);
      EXPECT_EQ(std::search(message.bytes.begin(), message.bytes.end(), fingerprint.begin(),
                            fingerprint.end()),
                message.bytes.end());
    }
  }
  // Statuses (queued, started, stages) and the five replies, all sealed.
  EXPECT_GE(sealed, 5);
}

}  // namespace
}  // namespace far::integration
