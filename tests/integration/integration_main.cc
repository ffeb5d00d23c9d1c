// far_integration_test's main. Besides running the tests, the binary is its own misbehaving
// client: `far_integration_test --far-half-writer <mode> <socket>` opens a session, prints
// "<session id> <segment name> <key hex>" on stdout, then writes part of an update and dies
// (tests/integration/session_lifetime_test.cc starts it with fork/exec: a forked copy of a
// multi-threaded test process must not go on to use LCM or malloc-heavy code), and
// `--far-simulator` is a well-behaved simulator (below), and
// `--far-other-user <socket>` is a well-behaved client that user_limits_test.cc runs as another
// uid, and `--far-hold ...` one that holds sessions, which fair_shares_test.cc runs as another
// uid (other_user_client.h).
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "daemon_process.h"
#include "integration_scenes.h"
#include "other_user_client.h"
#include "raw_session.h"
#include <gtest/gtest.h>

#include "far/protocol/convert.h"

namespace far::integration {
namespace {

int HalfWriterMain(const std::string& mode, const std::string& socket) {
  auto session = RawSession::Open(socket, TestLcmUrl(), "half-writer-" + mode);
  if (!session) {
    std::fprintf(stderr, "half-writer: %s\n", far::ToString(session.error()).c_str());
    return 2;
  }
  RawSession& raw = **session;
  std::string key;
  for (uint8_t b : raw.key()) {
    char hex[3];
    std::snprintf(hex, sizeof(hex), "%02x", b);
    key += hex;
  }
  std::printf("%lld %s %s\n", static_cast<long long>(raw.id()), raw.segment().name().c_str(),
              key.c_str());
  std::fflush(stdout);
  const protocol::RingRegion ring = raw.segment().update_ring();

  if (mode == "unpublished") {
    // Half of an add_object record in the ring; the write index never moves.
    const Mesh mesh = TriangleRow(1000);
    protocol::AddObjectRecord fixed{};
    fixed.header = {static_cast<uint32_t>(protocol::RecordType::kAddObject),
                    static_cast<uint32_t>(protocol::AddObjectRecordSize(3000, 1000)), 1};
    fixed.object_id = 1;
    fixed.vertex_count = 3000;
    fixed.triangle_count = 1000;
    fixed.X_WO[3] = 1;
    std::memcpy(ring.data, &fixed, sizeof(fixed));
    std::memcpy(ring.data + sizeof(fixed), mesh.p_MV.data(),
                mesh.p_MV.size() * sizeof(Eigen::Vector3d) / 2);
    _exit(0);
  }
  if (mode == "index-mid-record") {
    // Record 1 whole; record 2's header claims 4096 bytes, half of them are written and the
    // write index is published in the middle of it; then a step for both, and death.
    if (!raw.writer().AddObject(1, TriangleRow(2), Motion::kRigid, Pose{})) return 3;
    const uint64_t at = raw.writer().ring().write_index();
    const protocol::RecordHeader header{static_cast<uint32_t>(protocol::RecordType::kAddObject),
                                        4096, 2};
    std::memcpy(ring.data + at, &header, sizeof(header));
    std::memset(ring.data + at + sizeof(header), 0x11, 2048 - sizeof(header));
    ring.write_index->store(at + 2048, std::memory_order_release);
    if (!raw.SendStep(0, SmallRequest(), 2)) return 4;
    _exit(0);
  }
  if (mode == "killed") {
    // Writes large records as fast as it can (moving the daemon's read index itself so the
    // ring never fills) until the test SIGKILLs it, most likely in the middle of a memcpy.
    const Mesh mesh = TriangleRow(8000);
    for (uint32_t id = 1;; ++id) {
      (void)raw.writer().AddObject(id, mesh, Motion::kRigid, Pose{});
      ring.read_index->store(raw.writer().ring().write_index(), std::memory_order_release);
    }
  }
  std::fprintf(stderr, "half-writer: unknown mode '%s'\n", mode.c_str());
  return 2;
}

// `far_integration_test --far-simulator <socket> <steps>`: a simulator that uses far::client
// as any program would (default options but the socket, no recording asked for in code), so
// that FAR_RECORD alone decides whether it is recorded (record_replay_test.cc).
int SimulatorMain(const std::string& socket, int steps) {
  client::ClientOptions options;
  options.socket_path = socket;
  options.client_name = "test-simulator";
  auto client = client::Client::Connect(options);
  if (!client) {
    std::fprintf(stderr, "simulator: %s\n", far::ToString(client.error()).c_str());
    return 2;
  }
  const std::vector<SceneObject> objects = ContactSoup(kHealthySeed);
  for (const SceneObject& o : objects) {
    if (auto ok = (*client)->AddObject(o.id, o.mesh, o.motion, o.X_WO); !ok) return 3;
  }
  StepRequest request;
  request.method = Method::kBvh;
  request.distance = 0.5;  // many distance pairs: replies large enough for the reply ring
  request.output = Output::kDistancePairs;
  Pose moving = objects.front().X_WO;
  for (int step = 0; step < steps; ++step) {
    moving.translation.x() += 0.05;
    if (auto ok = (*client)->SetPose(objects.front().id, moving); !ok) return 4;
    auto result = (*client)->Step(request);
    if (!result) {
      std::fprintf(stderr, "simulator: %s\n", far::ToString(result.error()).c_str());
      return 5;
    }
    std::printf("step %d: %zu contacts, %zu distance pairs\n", step, result->contacts.size(),
                result->distance_pairs.size());
  }
  return 0;
}

}  // namespace
}  // namespace far::integration

int main(int argc, char** argv) {
  // LCM udpm traffic must stay inside a private network namespace (docs/daemon.md). ctest runs
  // this binary through deploy/netns-run.sh (the target's CROSSCOMPILING_EMULATOR); run by
  // hand, it re-executes itself through it.
  const char* in_netns = std::getenv("FAR_IN_NETNS");
  if (in_netns == nullptr || std::strcmp(in_netns, "1") != 0) {
    std::vector<char*> args = {const_cast<char*>(FAR_NETNS_RUN_PATH)};
    const std::string self = far::integration::SelfPath();
    args.push_back(const_cast<char*>(self.c_str()));
    for (int i = 1; i < argc; ++i) args.push_back(argv[i]);
    args.push_back(nullptr);
    execv(FAR_NETNS_RUN_PATH, args.data());
    std::fprintf(stderr, "far_integration_test: cannot run %s: %s\n", FAR_NETNS_RUN_PATH,
                 std::strerror(errno));
    return 1;
  }
  if (argc == 4 && std::strcmp(argv[1], "--far-half-writer") == 0) {
    return far::integration::HalfWriterMain(argv[2], argv[3]);
  }
  if (argc == 4 && std::strcmp(argv[1], "--far-simulator") == 0) {
    return far::integration::SimulatorMain(argv[2], std::atoi(argv[3]));
  }
  if (argc == 3 && std::strcmp(argv[1], "--far-other-user") == 0) {
    return far::integration::OtherUserClientMain(argv[2]);
  }
  if (argc == 6 && std::strcmp(argv[1], "--far-hold") == 0) {
    return far::integration::HoldingClientMain(argv[2], std::atoi(argv[3]), std::atoll(argv[4]),
                                               argv[5]);
  }
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
