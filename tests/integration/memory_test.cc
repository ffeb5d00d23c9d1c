// The daemon's memory: what large sessions take is given back when they close, the daemon-wide
// budget (max_triangles_total, max_vertices_total) refuses what one session would add while
// others hold it, a reply is capped (max_reply_pairs), steps do not make the daemon grow, a
// segment's descriptor kept after its session closed holds no memory, and a flood of large
// datagrams leaves none behind. Resident sizes are the daemon's VmRSS (/proc/<pid>/status).
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <thread>

#include "daemon_fixture.h"
#include "integration_scenes.h"
#include "raw_session.h"
#include <gtest/gtest.h>

#include "far/client/client.h"
#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/lcm_bus.h"
#include "far/scenes/scenes.h"

namespace far::integration {
namespace {

using namespace std::chrono_literals;

int SessionsOpen() {
  auto status = client::Client::Status(TestClientOptions("status"));
  return status ? status->sessions_open : -1;
}

// The daemon's resident size once every session is gone and its memory given back: no session
// open, no segment mapped, and VmRSS no longer falling.
int64_t SettledResidentKiB(DaemonProcess& daemon) {
  EXPECT_TRUE(WaitUntil(
      [&] { return SessionsOpen() == 0 && SessionSegmentsOf(daemon.pid()).empty(); }, 10s));
  int64_t last = ResidentKiB(daemon.pid());
  for (int i = 0; i < 15; ++i) {
    std::this_thread::sleep_for(200ms);
    const int64_t now = ResidentKiB(daemon.pid());
    if (now > last - 256) return now;
    last = now;
  }
  return last;
}

std::unique_ptr<client::Client> Connect(const std::string& name,
                                        std::chrono::milliseconds timeout = 10s) {
  auto client = client::Client::Connect(TestClientOptions(name, timeout));
  EXPECT_TRUE(client.ok()) << name << ": " << far::ToString(client.error());
  return client ? std::move(*client) : nullptr;
}

// A scene of about a million triangles (far::scenes::ScalingScene: ground, spheres, cloths).
const Scene& LargeScene() {
  static const Scene kScene = [] {
    Scene scene = scenes::ScalingScene(5, 1'000'000, 1);
    scene.frames.clear();
    return scene;
  }();
  return kScene;
}

// Opens a session on the daemon's socket as a hoarder would: asks for rings of `ring_bytes`,
// keeps the segment's descriptor and closes the connection at once, which ends the session.
// Returns the descriptor, or the daemon's refusal.
Result<int> OpenAndLeave(int64_t ring_bytes) {
  auto connection = protocol::LocalConnection::Connect(CurrentSocketPath());
  if (!connection) return connection.error();
  far_lcm::open_session_t open = MakeOpenSession("hoarder");
  open.update_ring_bytes = ring_bytes;
  open.reply_ring_bytes = ring_bytes;
  auto bytes = protocol::EncodeMessage(open);
  if (!bytes) return bytes.error();
  if (auto sent = connection->Send(*bytes); !sent) return sent.error();
  auto answer = connection->Receive(protocol::kMaxControlMessageBytes, 5s, /*accept_fd=*/true);
  if (!answer) return answer.error();
  auto reply = protocol::DecodeMessage<far_lcm::open_session_reply_t>(
      answer->bytes.data(), answer->bytes.size(), protocol::kMaxControlMessageBytes);
  if (!reply || reply->status != protocol::kWireOk || answer->fd < 0) {
    if (answer->fd >= 0) close(answer->fd);
    if (!reply) return reply.error();
    return MakeError(protocol::FromWireStatus(reply->status), reply->message);
  }
  return answer->fd;
}

// The memory the files behind `fds` hold (allocated blocks), in bytes.
int64_t AllocatedBytes(const std::vector<int>& fds) {
  int64_t bytes = 0;
  for (const int fd : fds) {
    struct stat info {};
    if (fstat(fd, &info) == 0) bytes += static_cast<int64_t>(info.st_blocks) * 512;
  }
  return bytes;
}

struct Descriptors {
  std::vector<int> fds;
  ~Descriptors() {
    for (const int fd : fds) close(fd);
  }
};

using MemoryTest = DaemonTest;

TEST_F(MemoryTest, ResidentSizeReturnsNearItsBaselineAfterLargeSessionsClose) {
  DaemonProcess* daemon = StartDaemon();
  ASSERT_NE(daemon, nullptr);
  // The first session makes what every later one shares (GL driver state, shaders): part of
  // the baseline, not of what sessions leave behind.
  ASSERT_TRUE(HealthyClientSteps("warm-up"));
  const int64_t baseline = SettledResidentKiB(*daemon);
  int64_t peak = 0;
  {
    std::vector<std::unique_ptr<client::Client>> clients;
    for (int i = 0; i < 4; ++i) {
      clients.push_back(Connect("large-" + std::to_string(i), 100s));
      ASSERT_NE(clients.back(), nullptr);
      ASSERT_TRUE(clients.back()->LoadScene(LargeScene()).ok());
      auto result = clients.back()->Step(SmallRequest(Method::kBvh));
      ASSERT_TRUE(result.ok()) << far::ToString(result.error());
      EXPECT_FALSE(result->contacts.empty());
    }
    peak = ResidentKiB(daemon->pid());
  }  // the clients close their sessions
  const int64_t after = SettledResidentKiB(*daemon);
  std::printf("daemon VmRSS: baseline %lld KiB, 4 large sessions %lld KiB, after close %lld KiB\n",
              static_cast<long long>(baseline), static_cast<long long>(peak),
              static_cast<long long>(after));
  // The sessions really held their scenes (4 x 1M triangles: hundreds of MB)...
  EXPECT_GT(peak - baseline, 400 * 1024);
  // ... and gave them back: within 16 MiB of the baseline. (Measured: within 0.2 MiB of it;
  // without the daemon's malloc_trim after sessions close, 240 MiB over it.)
  EXPECT_LE(after - baseline, 16 * 1024);
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(MemoryTest, TheDaemonWideBudgetRefusesAnUploadUntilTheSessionHoldingItCloses) {
  // Each session may have 2M triangles; all of them together 1000 triangles and 1000 vertices.
  DaemonProcess* daemon =
      StartDaemon({"--max-triangles-total", "1000", "--max-vertices-total", "1000"});
  ASSERT_NE(daemon, nullptr);
  auto holder = Connect("holder");
  auto late = Connect("late");
  ASSERT_NE(holder, nullptr);
  ASSERT_NE(late, nullptr);
  ASSERT_TRUE(holder->AddObject(1, FlatGrid(20), Motion::kRigid).ok());  // 441 v, 800 t
  ASSERT_TRUE(holder->Step(SmallRequest()).ok());

  // 300 more triangles: 1100 in all sessions.
  ASSERT_TRUE(late->AddObject(1, TriangleFan(300), Motion::kRigid).ok());  // 302 v, 300 t
  auto refused = late->Step(SmallRequest());
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kLimitExceeded);
  EXPECT_NE(refused.error().message.find(
                "max_triangles_total: user " + std::to_string(geteuid()) +
                " holds 800 of its share of 1000 triangles (1000 shared by 1 user); 300 more "
                "would pass its share, and 200 are free"),
            std::string::npos)
      << refused.error().message;
  // 600 more vertices: 1041 in all sessions.
  ASSERT_TRUE(late->AddObject(2, TriangleRow(200), Motion::kRigid).ok());  // 600 v, 200 t
  refused = late->Step(SmallRequest());
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("holds 441 of its share of 1000 vertices (1000 shared "
                                         "by 1 user); 600 more would pass its share, and 559 "
                                         "are free"),
            std::string::npos)
      << refused.error().message;
  EXPECT_TRUE(holder->Step(SmallRequest()).ok()) << "the holder is not disturbed";

  // Once the holder is gone, the same upload fits (refused batches reserved nothing). Its
  // worker gives the budget back as it ends, just before it unmaps the segment.
  ASSERT_TRUE(holder->Close().ok());
  ASSERT_TRUE(WaitUntil([&] { return SessionSegmentsOf(daemon->pid()).size() == 1; }, 3s));
  ASSERT_TRUE(late->AddObject(1, TriangleFan(300), Motion::kRigid).ok());
  auto accepted = late->Step(SmallRequest());
  EXPECT_TRUE(accepted.ok()) << far::ToString(accepted.error());
  auto status = client::Client::Status(TestClientOptions("status"));
  ASSERT_TRUE(status.ok());
  ASSERT_EQ(status->sessions.size(), 1u);
  EXPECT_EQ(status->sessions[0].triangles, 300);
}

TEST_F(MemoryTest, AReplyOverTheReplyPairCapFailsNamingItAndTheDaemonGoesOn) {
  ASSERT_NE(StartDaemon({"--max-reply-pairs", "100"}), nullptr);
  auto client = Connect("near-planes");
  ASSERT_NE(client, nullptr);
  // Two parallel grids of 200 triangles 0.05 apart: no contacts, thousands of pairs within 0.1.
  Pose above;
  above.translation.z() = 0.05;
  ASSERT_TRUE(client->AddObject(1, FlatGrid(10), Motion::kRigid).ok());
  ASSERT_TRUE(client->AddObject(2, FlatGrid(10), Motion::kRigid, above).ok());
  StepRequest request = SmallRequest(Method::kBvh);
  request.output = Output::kDistancePairs;
  request.distance = 0.1;
  auto capped = client->Step(request);
  ASSERT_FALSE(capped.ok());
  EXPECT_EQ(capped.error().code, ErrorCode::kLimitExceeded);
  EXPECT_NE(capped.error().message.find("more than 100 contact and distance pairs, the most a "
                                        "reply may carry"),
            std::string::npos)
      << capped.error().message;
  // A query within the cap, in the same session, and another session: both served.
  request.distance = 0.01;
  auto next = client->Step(request);
  ASSERT_TRUE(next.ok()) << far::ToString(next.error());
  EXPECT_TRUE(next->distance_pairs.empty());
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(MemoryTest, ThousandsOfStepsDoNotGrowTheDaemon) {
  // A 1 MiB update ring: the ring's shared pages are all touched (and so resident) within the
  // warm-up, so that what remains is what steps allocate and keep. (With the default 64 MiB
  // ring, VmRSS grows by the bytes each step writes until the ring has wrapped once: bounded by
  // the ring, and freed with the session; docs/daemon.md.)
  DaemonProcess* daemon = StartDaemon({"--ring-bytes", "1048576"});
  ASSERT_NE(daemon, nullptr);
  auto client = Connect("long-runner");
  ASSERT_NE(client, nullptr);
  Scene scene;
  scene.objects = ContactSoup(kHealthySeed);
  ASSERT_TRUE(client->LoadScene(scene).ok());
  const StepRequest request = SmallRequest(Method::kBvh);
  // Every step moves every object (ring records, pose updates) and is answered with contacts.
  auto step = [&](int i) {
    for (const SceneObject& object : scene.objects) {
      Pose pose = object.X_WO;
      pose.translation.x() += 0.01 * std::sin(0.05 * i + object.id);
      if (!client->SetPose(object.id, pose).ok()) return false;
    }
    return client->Step(request).ok();
  };
  // Warm-up: the ring wraps, the latency windows (1024 steps per session, 8192 in all) fill,
  // the allocator settles.
  constexpr int kWarmUp = 10'000, kSteps = 20'000;
  for (int i = 0; i < kWarmUp; ++i) ASSERT_TRUE(step(i)) << "step " << i;
  const int64_t before = ResidentKiB(daemon->pid());
  const int64_t anon_before = ResidentKiB(daemon->pid(), "RssAnon");
  const int64_t shmem_before = ResidentKiB(daemon->pid(), "RssShmem");
  for (int i = kWarmUp; i < kWarmUp + kSteps; ++i) ASSERT_TRUE(step(i)) << "step " << i;
  const int64_t after = ResidentKiB(daemon->pid());
  std::printf("RssAnon %lld -> %lld, RssShmem %lld -> %lld KiB\n",
              static_cast<long long>(anon_before),
              static_cast<long long>(ResidentKiB(daemon->pid(), "RssAnon")),
              static_cast<long long>(shmem_before),
              static_cast<long long>(ResidentKiB(daemon->pid(), "RssShmem")));
  const double bytes_per_step = (after - before) * 1024.0 / kSteps;
  std::printf("daemon VmRSS %lld -> %lld KiB over %d steps: %.1f bytes per step\n",
              static_cast<long long>(before), static_cast<long long>(after), kSteps,
              bytes_per_step);
  // Issue 10 measured 2.2 KB per step. Here: 0 to 8 bytes per step (allocator noise, in
  // RssAnon); latency windows that kept every sample (8 bytes a step, twice) measured 35.
  EXPECT_LT(bytes_per_step, 20.0);
}

TEST_F(MemoryTest, SegmentDescriptorsKeptAfterTheirSessionsClosedHoldNoMemory) {
  // Issue 41: 40 sessions opened, each segment's descriptor kept, each session closed. Every
  // kept segment held its memory (80 MiB at the default ring sizes: +3,200 MiB while the daemon
  // showed no session, and no limit counted it). Rings of 1 MiB here: what counts is that the
  // kept descriptors hold nothing once their sessions are gone. (A higher open rate than the
  // default 20/s keeps the test short, and leaves the healthy client's open after it a token.)
  DaemonProcess* daemon = StartDaemon({"--max-opens-per-second", "200"});
  ASSERT_NE(daemon, nullptr);
  Descriptors kept;
  int refused = 0;
  while (kept.fds.size() < 40 && refused < 400) {
    auto fd = OpenAndLeave(1 << 20);
    if (fd) {
      kept.fds.push_back(*fd);
      continue;
    }
    // The open rate, or the user's session limit before the daemon saw the last ones go.
    ASSERT_TRUE(fd.error().code == ErrorCode::kBusy || fd.error().code == ErrorCode::kLimitExceeded)
        << far::ToString(fd.error());
    ++refused;
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_EQ(kept.fds.size(), 40u);
  ASSERT_TRUE(WaitUntil([] { return SessionsOpen() == 0; }, 5s));
  EXPECT_TRUE(WaitUntil([&] { return AllocatedBytes(kept.fds) == 0; }, 1s))
      << AllocatedBytes(kept.fds) << " bytes are held by the segments of 40 closed sessions";
  EXPECT_TRUE(WaitUntil([&] { return SessionSegmentsOf(daemon->pid()).empty(); }, 2s));
  EXPECT_TRUE(HealthyClientSteps());
}

TEST_F(MemoryTest, AFloodOfLargeDatagramsLeavesNoMemoryInTheDaemon) {
  // Issue 41: 60 KB datagrams on the daemon's request channels for a few seconds left +73 MB
  // in it (LCM's receive ring grew and never shrank: the patch's hunks 9-11).
  DaemonProcess* daemon = StartDaemon();
  ASSERT_NE(daemon, nullptr);
  ASSERT_TRUE(HealthyClientSteps("warm-up"));
  const int64_t before = SettledResidentKiB(*daemon);
  auto status = client::Client::Status(TestClientOptions("status"));
  ASSERT_TRUE(status.ok());
  auto bus = protocol::LcmBus::Create(TestLcmUrl());
  ASSERT_TRUE(bus.ok());
  const std::vector<uint8_t> payload(60'000, 0x41);
  const auto start = std::chrono::steady_clock::now();
  int64_t sent = 0;
  while (std::chrono::steady_clock::now() - start < 2s) {
    const std::string channel =
        protocol::SessionRequestChannel(status->channel_prefix, 1 + sent % 100);
    if ((*bus)->Publish(channel, payload)) ++sent;
  }
  const int64_t during = ResidentKiB(daemon->pid());
  std::this_thread::sleep_for(1s);  // the daemon drains what it queued
  const int64_t after = SettledResidentKiB(*daemon);
  std::printf(
      "%lld datagrams of 60 KB; daemon VmRSS %lld KiB before, %lld at the end, %lld after\n",
      static_cast<long long>(sent), static_cast<long long>(before), static_cast<long long>(during),
      static_cast<long long>(after));
  // Measured after the fix: +0.1 MiB (before it: +30 to +45 MiB on 2 loaded cores).
  EXPECT_LE(after - before, 8 * 1024);
  EXPECT_TRUE(daemon->Running());
  EXPECT_TRUE(HealthyClientSteps());
}

}  // namespace
}  // namespace far::integration
