// Fuzz target daemon_datagram: what far-daemon does with the LCM datagrams it receives. A fresh
// daemon message stack per input (DaemonConfig, SessionRegistry, Replier, MessageHandlers
// subscribed on an in-process memq:// LcmBus, exactly as Daemon wires them; no socket and no
// worker threads) with two sessions open (1 and 2, opened through SessionRegistry::Open as the
// socket server opens them: real memfd segments and fresh keys) gets a sequence of datagrams.
// A datagram may ask the harness to sign it with its channel's session key, so authenticated
// step requests reach validation, the request rate and the step queue; the harness may also
// play the sessions' workers (take the queued steps) and close a session.
//
// Input: datagrams until the bytes run out, each
//   uint8  channel    % 6: 0..2 FAR_S1_REQ..FAR_S3_REQ (session 3 is never open),
//                     3 "FAR_S" + digits + "_REQ" (uint8 length, then bytes mapped to digits),
//                     4 FAR_GPU_1_S1_REQ (another daemon's channel),
//                     5 any name (uint8 length, then the bytes; at most 63, no "REPLY")
//   uint8  flags      bit 0: sign the payload with the key of the channel's session (if open);
//                     bit 1: afterwards the workers take every queued step;
//                     bit 2: afterwards the channel's session is closed
//   uint16 length     payload bytes (host order), then the payload
//
// Oracles besides the sanitizers: the daemon publishes only on the reply channels of the
// sessions it has opened; everything it publishes opens with that session's key (sealed_t),
// in strictly increasing sequence, and holds a step_reply_t, step_status_t or error_t of that
// session; a queued step is a validated request within max_resolution, and a session's queue
// never holds more than max_queued_per_session steps.

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "daemon_config.h"
#include "daemon_stats.h"
#include "fuzz_input.h"
#include "message_handlers.h"
#include "replier.h"
#include "session_registry.h"
#include <spdlog/spdlog.h>

#include "far/model/step_request.h"
#include "far/protocol/channels.h"
#include "far/protocol/lcm_bus.h"
#include "far/protocol/message.h"
#include "far/protocol/session_auth.h"

namespace far::fuzz {
namespace {

using protocol::MessageType;

constexpr int kOpenSessions = 2;

server::DaemonConfig FuzzConfig() {
  server::DaemonConfig config;
  config.lcm_url = "memq://";
  config.ring_bytes = protocol::kMinRingCapacity;  // small segments: cheap opens
  config.reply_bytes = protocol::kMinRingCapacity;
  config.max_resolution = 1024;
  // A burst of 8 requests and then (within an input's milliseconds) none: the rate limit is
  // reached by long inputs, the same way every time.
  config.max_requests_per_second = 0.001;
  return config;
}

// The channel of one datagram; empty when the input names none it could send on.
std::string ChannelOf(uint8_t selector, FuzzInput& in) {
  switch (selector % 6) {
    case 0:
    case 1:
    case 2:
      return protocol::SessionRequestChannel("FAR_", selector % 6 + 1);
    case 3: {
      std::string digits;
      for (uint8_t b : in.TakeBytes(in.Take<uint8_t>() % 24)) digits += char('0' + b % 10);
      return "FAR_S" + digits + "_REQ";
    }
    case 4:
      return protocol::SessionRequestChannel(protocol::ChannelPrefix("gpu-1"), 1);
    default: {
      auto name = in.TakeBytes(in.Take<uint8_t>() % 64);
      std::string channel(name.begin(), name.end());
      if (channel.find("REPLY") != std::string::npos) return {};
      return channel;
    }
  }
}

// What a session's client knows: its key, and the daemon's last sequence number.
struct ClientView {
  protocol::SessionKey key{};
  int64_t last_sealed_id = 0;
};

// Checks one message the daemon published on a reply channel, as the session's client reads it.
void CheckPublished(std::map<std::string, std::pair<int64_t, ClientView>>& clients,
                    const std::string& channel, std::span<const uint8_t> bytes) {
  auto it = clients.find(channel);
  FAR_FUZZ_CHECK(it != clients.end());  // only the reply channels of opened sessions
  auto& [session_id, client] = it->second;
  auto opened = protocol::OpenSealed(bytes.data(), bytes.size(), session_id, client.key,
                                     protocol::kMaxStepReplyBytes);
  FAR_FUZZ_CHECK(opened);
  FAR_FUZZ_CHECK(opened->request_id > client.last_sealed_id);
  client.last_sealed_id = opened->request_id;
  const auto& inner = opened->inner;
  auto type = protocol::IdentifyMessage(inner.data(), inner.size());
  FAR_FUZZ_CHECK(type);
  int64_t inner_session = 0;
  if (*type == MessageType::kStepReply) {
    auto m = protocol::DecodeMessage<far_lcm::step_reply_t>(inner.data(), inner.size(),
                                                            protocol::kMaxStepReplyBytes);
    FAR_FUZZ_CHECK(m && !m->reply_in_shm);
    inner_session = m->session_id;
  } else if (*type == MessageType::kStepStatus) {
    auto m = protocol::DecodeMessage<far_lcm::step_status_t>(inner.data(), inner.size(),
                                                             protocol::kMaxControlMessageBytes);
    FAR_FUZZ_CHECK(m);
    inner_session = m->session_id;
  } else {
    FAR_FUZZ_CHECK(*type == MessageType::kError);
    auto m = protocol::DecodeMessage<far_lcm::error_t>(inner.data(), inner.size(),
                                                       protocol::kMaxControlMessageBytes);
    FAR_FUZZ_CHECK(m);
    inner_session = m->session_id;
  }
  FAR_FUZZ_CHECK(inner_session == session_id);
}

// The daemon's message side, as Daemon wires it, on its own memq:// bus.
struct DaemonUnderTest {
  server::DaemonConfig config = FuzzConfig();
  std::unique_ptr<protocol::LcmBus> bus;
  server::DaemonStats stats;
  SharedSceneBudget budget{server::BudgetTotalsOf(config)};
  server::SessionRegistry sessions{config, budget};
  std::unique_ptr<server::Replier> replier;
  std::unique_ptr<server::MessageHandlers> handlers;
  std::map<std::string, std::pair<int64_t, ClientView>> clients;  // by reply channel
  uint64_t dispatched = 0;

  DaemonUnderTest() {
    auto created = protocol::LcmBus::Create(config.lcm_url);
    FAR_FUZZ_CHECK(created);
    bus = std::move(*created);
    replier = std::make_unique<server::Replier>(*bus, stats);
    handlers = std::make_unique<server::MessageHandlers>(config, sessions, *replier, stats);
    handlers->Subscribe(*bus);
    for (int i = 0; i < kOpenSessions; ++i) {
      protocol::OpenSessionParams params;
      params.client_name = "fuzz";
      auto session = sessions.Open(params, protocol::PeerCredentials{1, 1000, 1000});
      FAR_FUZZ_CHECK(session);
      clients[(*session)->reply_channel] = {(*session)->id, ClientView{(*session)->key, 0}};
    }
    // Everything on the bus; the harness never sends on a name with "REPLY".
    bus->Subscribe(".*", [this](std::string_view channel, std::span<const uint8_t> bytes) {
      ++dispatched;
      if (channel.find("REPLY") != std::string_view::npos)
        CheckPublished(clients, std::string(channel), bytes);
    });
  }

  // Publishes one datagram and handles messages until the bus is quiet. libFuzzer's -timeout
  // alarm (SIGALRM) may interrupt LCM's select (EINTR, Handle false): that wait is tried again.
  void Deliver(const std::string& channel, std::span<const uint8_t> payload) {
    if (!bus->Publish(channel, payload)) return;
    for (;;) {
      const uint64_t before = dispatched;
      errno = 0;
      if (!bus->Handle(std::chrono::milliseconds(0))) {
        FAR_FUZZ_CHECK(errno == EINTR);
        continue;
      }
      if (dispatched == before) return;
    }
  }

  std::shared_ptr<server::Session> SessionOf(const std::string& channel) const {
    const auto id = protocol::ParseSessionRequestChannel("FAR_", channel);
    return id ? sessions.Find(*id) : nullptr;
  }

  // The payload signed with the key of the session whose request channel this is, as a client
  // holding the key would sign it; unchanged when there is no such open session.
  std::vector<uint8_t> Signed(const std::string& channel, std::span<const uint8_t> payload) {
    std::vector<uint8_t> bytes(payload.begin(), payload.end());
    if (const auto session = SessionOf(channel)) (void)protocol::SignEncoded(bytes, session->key);
    return bytes;
  }

  // Checks every session's queue; with `take`, empties it as the session's worker would.
  void CheckQueues(bool take) {
    for (const auto& session : sessions.Sessions()) {
      std::lock_guard lock(session->mutex);
      FAR_FUZZ_CHECK(session->queue.size() <= static_cast<size_t>(config.max_queued_per_session));
      for (const server::StepJob& job : session->queue) {
        FAR_FUZZ_CHECK(job.command.session_id == session->id);
        FAR_FUZZ_CHECK(job.command.request.resolution <= config.max_resolution);
        FAR_FUZZ_CHECK(CheckStepRequest(job.command.request).ok());
        FAR_FUZZ_CHECK(job.deadline >= job.received);
      }
      if (take) session->queue.clear();
    }
  }
};

}  // namespace
}  // namespace far::fuzz

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  spdlog::set_level(spdlog::level::off);  // a log line per rejected datagram is only noise here
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace far::fuzz;
  FuzzInput in(data, size);
  DaemonUnderTest daemon;
  while (!in.empty()) {
    const std::string channel = ChannelOf(in.Take<uint8_t>(), in);
    const uint8_t flags = in.Take<uint8_t>();
    const auto payload = in.TakeBytes(in.Take<uint16_t>());
    if (channel.empty()) continue;
    if (flags & 1) {
      daemon.Deliver(channel, daemon.Signed(channel, payload));
    } else {
      daemon.Deliver(channel, payload);
    }
    daemon.CheckQueues(flags & 2);
    if (flags & 4) {
      if (const auto session = daemon.SessionOf(channel)) daemon.sessions.Close(session->id);
    }
  }
  return 0;
}
