// End to end through real processes: far-client collide/play against far-daemon give the
// brute-force reference's answers; concurrent sessions with the same ids and interpenetrating
// geometry never see each other; far-client status reports what happened.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <future>

#include "daemon_fixture.h"
#include "integration_scenes.h"
#include "raw_session.h"
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "far/client/client.h"
#include "far/io/scene_io.h"
#include "far/pipeline/pipeline.h"
#include "far/protocol/convert.h"

namespace far::integration {
namespace {

using nlohmann::json;

// The [objA, triA, objB, triB(, d)] arrays of far-client's JSON as sorted id quadruples.
std::vector<ContactPair> PairsFromJson(const json& array) {
  std::vector<ContactPair> pairs;
  for (const json& p : array) {
    pairs.push_back({p.at(0).get<uint32_t>(), p.at(1).get<uint32_t>(), p.at(2).get<uint32_t>(),
                     p.at(3).get<uint32_t>()});
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

// Writes `objects` as a scene file in `dir` and returns what a reader of that file gets (the
// objects far-client uploads), so the reference is computed on exactly those.
std::vector<SceneObject> WriteAndReadBack(const std::vector<SceneObject>& objects,
                                          const std::filesystem::path& path) {
  Scene scene;
  scene.objects = objects;
  auto written = WriteScene(scene, path);
  EXPECT_TRUE(written.ok()) << (written.ok() ? "" : far::ToString(written.error()));
  auto read = ReadScene(path);
  EXPECT_TRUE(read.ok()) << (read.ok() ? "" : far::ToString(read.error()));
  return read.ok() ? read->objects : std::vector<SceneObject>{};
}

using EndToEndTest = DaemonTest;

TEST_F(EndToEndTest, CollideGivesTheBruteForceContactsForEveryMethod) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const auto path = dir.path() / "soup.json";
  const std::vector<SceneObject> objects = WriteAndReadBack(ContactSoup(3), path);
  ASSERT_FALSE(objects.empty());
  const std::vector<ContactPair> expected = ReferenceContacts(objects);
  ASSERT_GE(expected.size(), 3u) << "the scene must have several contacts";

  for (const char* method : {"far", "far-exact-offset", "aabb", "exact"}) {
    SCOPED_TRACE(method);
    const ProcessResult run =
        RunFarClient({"collide", path.string(), "--method", method, "--resolution", "256"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const json out = json::parse(run.out, nullptr, /*allow_exceptions=*/false);
    ASSERT_FALSE(out.is_discarded()) << "stdout is not JSON: " << run.out;
    const auto contacts = PairsFromJson(out.at("contacts"));
    EXPECT_EQ(contacts, expected) << "got " << ToString(contacts) << "\nexpected "
                                  << ToString(expected);
    // The certificate travels with the answer: why nothing was missed, and for the GPU
    // methods each level's numbers, which must cover what they claim.
    const json& certificate = out.at("stats").at("certificate");
    EXPECT_TRUE(certificate.at("guaranteed").get<bool>()) << certificate.dump();
    EXPECT_EQ(certificate.at("basis").get<std::string>().rfind("guaranteed: ", 0), 0u);
    const bool gpu = std::string(method).rfind("far", 0) == 0;
    ASSERT_EQ(certificate.at("levels").size(), gpu ? 2u : 0u) << certificate.dump();
    for (const json& level : certificate.at("levels")) {
      EXPECT_EQ(level.at("resolution").get<int>(), 256);
      const double covered = std::sqrt(3.0) * std::max(level.at("pixel_size").get<double>(),
                                                       level.at("depth_step").get<double>()) +
                             level.at("rounding").get<double>();
      EXPECT_GE(level.at("offset_radius").get<double>(), covered) << level.dump();
      EXPECT_GT(level.at("pixel_size").get<double>(), 0) << level.dump();
    }
  }
}

// One id range everywhere: a scene far-client reads (ids are any uint32) is one the daemon
// accepts, and its replies carry the ids back unchanged, 0 and 2^32 - 1 included.
TEST_F(EndToEndTest, EveryUint32IdRoundTripsThroughTheDaemon) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const auto path = dir.path() / "ids.json";
  std::vector<SceneObject> soup = ContactSoup(3);
  const uint32_t ids[] = {0u, 0x7FFFFFFFu, 0x80000000u, 0xFFFFFFFEu, 0xFFFFFFFFu};
  for (size_t i = 0; i < soup.size() && i < std::size(ids); ++i) soup[i].id = ids[i];
  const std::vector<SceneObject> objects = WriteAndReadBack(soup, path);
  ASSERT_FALSE(objects.empty());
  const std::vector<ContactPair> expected = ReferenceContacts(objects);
  // The scene must have contacts that name the extreme ids.
  ASSERT_TRUE(std::any_of(expected.begin(), expected.end(), [](const ContactPair& c) {
    return c.object_a == 0u || c.object_b == 0xFFFFFFFFu || c.object_b == 0x80000000u;
  })) << ToString(expected);
  for (const char* method : {"far", "aabb", "exact"}) {
    SCOPED_TRACE(method);
    const ProcessResult run =
        RunFarClient({"collide", path.string(), "--method", method, "--resolution", "128"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const json out = json::parse(run.out, nullptr, /*allow_exceptions=*/false);
    ASSERT_FALSE(out.is_discarded()) << "stdout is not JSON: " << run.out;
    EXPECT_EQ(PairsFromJson(out.at("contacts")), expected);
  }
}

TEST_F(EndToEndTest, CollideWithDistanceGivesTheBruteForceDistancePairs) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const auto path = dir.path() / "soup.json";
  const std::vector<SceneObject> objects = WriteAndReadBack(ContactSoup(3), path);
  ASSERT_FALSE(objects.empty());
  constexpr double kDistance = 0.05;
  const std::vector<ContactPair> expected = ReferenceDistancePairs(objects, kDistance);
  const std::vector<ContactPair> contacts = ReferenceContacts(objects);
  // Pairs within D include the touching ones and some that only come close.
  ASSERT_GT(expected.size(), contacts.size());

  for (const char* method : {"far", "exact"}) {
    SCOPED_TRACE(method);
    const ProcessResult run =
        RunFarClient({"collide", path.string(), "--method", method, "--resolution", "256",
                      "--distance", "0.05", "--output", "distance"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const json out = json::parse(run.out, nullptr, false);
    ASSERT_FALSE(out.is_discarded()) << run.out;
    const auto pairs = PairsFromJson(out.at("distance_pairs"));
    EXPECT_EQ(pairs, expected) << "got " << ToString(pairs) << "\nexpected " << ToString(expected);
    for (const json& p : out.at("distance_pairs")) {
      EXPECT_LE(p.at(4).get<double>(), kDistance);
      EXPECT_GE(p.at(4).get<double>(), 0.0);
    }
  }
}

// The library does what far-client --distance does: a distance with the output left at its
// default asks for the distance pairs, not for contacts only and an empty list without a word.
TEST_F(EndToEndTest, LibraryStepWithADistanceAndNoOutputGivesTheDistancePairs) {
  ASSERT_NE(StartDaemon(), nullptr);
  const std::vector<SceneObject> objects = ContactSoup(3);
  constexpr double kDistance = 0.05;
  const std::vector<ContactPair> expected = ReferenceDistancePairs(objects, kDistance);
  ASSERT_GT(expected.size(), ReferenceContacts(objects).size());
  auto client = client::Client::Connect(TestClientOptions("distance"));
  ASSERT_TRUE(client.ok()) << far::ToString(client.error());
  ASSERT_TRUE((*client)->LoadScene(Scene{objects, {}}).ok());

  // aabb: its exact stage looks for distance pairs only when the output asks for them (exact,
  // the brute force, always does, and could not tell).
  StepRequest request = SmallRequest(Method::kAabb);
  request.distance = kDistance;
  ASSERT_EQ(request.output, Output::kContacts);  // the default, as a library user leaves it
  auto result = (*client)->Step(request);
  ASSERT_TRUE(result.ok()) << far::ToString(result.error());
  std::vector<ContactPair> pairs;
  for (const DistancePair& d : result->distance_pairs) pairs.push_back(d.pair);
  std::sort(pairs.begin(), pairs.end());
  EXPECT_EQ(pairs, expected) << "got " << ToString(pairs) << "\nexpected " << ToString(expected);
  EXPECT_EQ(result->contacts, ReferenceContacts(objects));

  // Any other output is sent as given: the PCS only, no exact stage, no pairs.
  request.output = Output::kPrimitivePcs;
  auto pcs = (*client)->Step(request);
  ASSERT_TRUE(pcs.ok()) << far::ToString(pcs.error());
  EXPECT_TRUE(pcs->distance_pairs.empty());
  EXPECT_TRUE(pcs->contacts.empty());
  EXPECT_FALSE(pcs->pcs_primitives.empty());
}

// Contact geometry through the daemon (StepRequest::geometry, protocol version 4) is the
// in-process pipeline's, bit for bit, for contacts and distance pairs, and far-client collide
// --geometry prints it.
TEST_F(EndToEndTest, GeometryThroughTheDaemonIsThePipelinesBitForBit) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const auto path = dir.path() / "soup.json";
  const std::vector<SceneObject> objects = WriteAndReadBack(ContactSoup(3), path);
  ASSERT_FALSE(objects.empty());
  auto client = client::Client::Connect(TestClientOptions("geometry"));
  ASSERT_TRUE(client.ok()) << far::ToString(client.error());
  ASSERT_TRUE((*client)->LoadScene(Scene{objects, {}}).ok());
  PipelineOptions options;
  options.use_gl = false;
  auto pipeline = Pipeline::Create(options);
  ASSERT_TRUE(pipeline.ok());
  ASSERT_TRUE((*pipeline)->LoadScene(Scene{objects, {}}).ok());

  StepRequest request = SmallRequest(Method::kBvh);
  request.distance = 0.05;
  request.output = Output::kDistancePairs;
  request.geometry = true;
  auto remote = (*client)->Step(request);
  ASSERT_TRUE(remote.ok()) << far::ToString(remote.error());
  auto local = (*pipeline)->Step(request);
  ASSERT_TRUE(local.ok()) << far::ToString(local.error());
  ASSERT_FALSE(remote->contacts.empty());
  ASSERT_EQ(remote->contacts, local->contacts);
  ASSERT_EQ(remote->contact_geometry.size(), remote->contacts.size());
  for (size_t i = 0; i < remote->contacts.size(); ++i) {
    const ContactGeometry& r = remote->contact_geometry[i];
    const ContactGeometry& l = local->contact_geometry[i];
    ASSERT_EQ(r.num_points, l.num_points) << i;
    for (int k = 0; k < r.num_points; ++k) EXPECT_EQ(r.points[k], l.points[k]) << i;
    EXPECT_EQ(r.normal_a, l.normal_a);
    EXPECT_EQ(r.normal_b, l.normal_b);
  }
  ASSERT_EQ(remote->closest_points.size(), remote->distance_pairs.size());
  for (size_t i = 0; i < remote->closest_points.size(); ++i) {
    EXPECT_EQ(remote->closest_points[i].point_a, local->closest_points[i].point_a);
    EXPECT_EQ(remote->closest_points[i].point_b, local->closest_points[i].point_b);
  }
  ASSERT_EQ(remote->penetrations.size(), local->penetrations.size());
  EXPECT_EQ(remote->stats.stages.back().stage, Stage::kGeometry);

  const ProcessResult run =
      RunFarClient({"collide", path.string(), "--method", "bvh", "--geometry"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const json out = json::parse(run.out, nullptr, false);
  ASSERT_FALSE(out.is_discarded()) << run.out;
  ASSERT_EQ(out.at("contact_geometry").size(), out.at("contacts").size());
  const json& first = out.at("contact_geometry").at(0);
  EXPECT_GE(first.at("points").size(), 1u);
  EXPECT_EQ(first.at("normal_a").size(), 3u);
  EXPECT_TRUE(out.contains("penetrations"));
  // Geometry with an output that has no pairs is refused with the field named.
  const ProcessResult refused =
      RunFarClient({"collide", path.string(), "--output", "pcs", "--geometry"});
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("geometry"), std::string::npos) << refused.err;
}

TEST_F(EndToEndTest, PlayRunsEveryFrameOfAMadeScene) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const auto path = dir.path() / "demo" / "scene.json";
  const ProcessResult made =
      RunFarClient({"make-scene", path.string(), "--leaves", "4", "--frames", "4", "--cells", "2"});
  ASSERT_EQ(made.exit_code, 0) << made.err;
  auto scene = ReadScene(path);
  ASSERT_TRUE(scene.ok()) << far::ToString(scene.error());

  const ProcessResult played = RunFarClient({"play", path.string(), "--resolution", "128"});
  ASSERT_EQ(played.exit_code, 0) << played.err;
  size_t steps = 0;
  std::istringstream lines(played.out);
  for (std::string line; std::getline(lines, line);) steps += line.rfind("step", 0) == 0;
  EXPECT_EQ(steps, scene->frames.size() + 1) << played.out;
}

TEST_F(EndToEndTest, LoadRunsEveryClientForItsStepsAndTime) {
  ASSERT_NE(StartDaemon(), nullptr);
  // By step count: every client, each with its own session, does all of its steps.
  ProcessResult load =
      RunFarClient({"load", "--clients", "3", "--steps", "4", "--resolution", "64", "--json"});
  ASSERT_EQ(load.exit_code, 0) << load.out << load.err;
  auto report = nlohmann::json::parse(load.out);
  ASSERT_EQ(report["per_client"].size(), 3u);
  for (const auto& client : report["per_client"]) {
    EXPECT_EQ(client["steps"].get<int>(), 4) << client.dump();
    EXPECT_EQ(client["errors"].get<int>(), 0) << client.dump();
  }
  EXPECT_EQ(report["overall"]["steps"].get<int>(), 12);
  EXPECT_DOUBLE_EQ(report["overall"]["fairness_max_over_min_steps"].get<double>(), 1.0);
  // By time: every client gets steps (all start together).
  load = RunFarClient({"load", "--clients", "3", "--steps", "0", "--seconds", "1.5", "--resolution",
                       "64", "--json"});
  ASSERT_EQ(load.exit_code, 0) << load.out << load.err;
  report = nlohmann::json::parse(load.out);
  for (const auto& client : report["per_client"])
    EXPECT_GT(client["steps"].get<int>(), 0) << client.dump();
}

// --client-cpu-ms: each client burns that much of its own thread's CPU before each step, so
// its run lasts at least steps x ms of wall time (CPU time never outruns it), and the report
// says how much was burned.
TEST_F(EndToEndTest, LoadBurnsTheClientCpuItIsToldBeforeEachStep) {
  ASSERT_NE(StartDaemon(), nullptr);
  constexpr int kSteps = 5;
  constexpr double kBurnMs = 20;
  const ProcessResult load =
      RunFarClient({"load", "--clients", "2", "--steps", std::to_string(kSteps), "--method", "aabb",
                    "--client-cpu-ms", "20", "--json"});
  ASSERT_EQ(load.exit_code, 0) << load.out << load.err;
  const auto report = nlohmann::json::parse(load.out);
  const auto& overall = report["overall"];
  EXPECT_GE(overall["seconds"].get<double>(), kSteps * kBurnMs / 1000) << overall.dump();
  EXPECT_DOUBLE_EQ(overall["client_cpu_ms_per_step"].get<double>(), kBurnMs);
  EXPECT_GE(overall["client_cpu_ms_total"].get<double>(), 2 * kSteps * kBurnMs) << overall.dump();
  ASSERT_EQ(report["per_client"].size(), 2u);
  for (const auto& client : report["per_client"]) {
    EXPECT_EQ(client["steps"].get<int>(), kSteps) << client.dump();
    EXPECT_GE(client["client_cpu_ms_total"].get<double>(), kSteps * kBurnMs) << client.dump();
  }
  // The text report says it too; without the flag nothing is burned.
  const ProcessResult text = RunFarClient(
      {"load", "--clients", "1", "--steps", "2", "--method", "aabb", "--client-cpu-ms", "20"});
  ASSERT_EQ(text.exit_code, 0) << text.out << text.err;
  EXPECT_NE(text.out.find("client CPU burned: 20.0 ms per step"), std::string::npos) << text.out;
  const ProcessResult none =
      RunFarClient({"load", "--clients", "1", "--steps", "2", "--method", "aabb", "--json"});
  ASSERT_EQ(none.exit_code, 0) << none.out << none.err;
  EXPECT_EQ(nlohmann::json::parse(none.out)["overall"]["client_cpu_ms_total"].get<double>(), 0);
}

// Sixteen sessions culling on the GL path at once, each on its own thread and context: on
// llvmpipe (Mesa 22.3.6) this killed far-daemon with SIGSEGV inside swrast_dri.so in 4 of 6
// six-second runs, because the contexts share one rasterizer; far::LockGl makes their GL stages
// take turns. The crash came with the sessions demoted (SCHED_IDLE; with none demoted it was
// not seen in 6 runs): heavy_step_ms 1 demotes every session here, as wall-time demotion did
// when the crash was met.
TEST_F(EndToEndTest, SixteenSessionsOnTheGlPathAtOnceLeaveTheDaemonUp) {
  TempDir dir;
  const auto config = dir.path() / "far.json";
  {
    std::ofstream out(config);
    out << R"({"heavy_step_ms": 1})";
  }
  DaemonProcess* daemon = StartDaemon({"--config", config.string()});
  ASSERT_NE(daemon, nullptr);
  const ProcessResult load =
      RunFarClient({"load", "--clients", "16", "--steps", "0", "--seconds", "4", "--method", "far",
                    "--resolution", "256", "--json"});
  ASSERT_EQ(load.exit_code, 0) << load.out << load.err;
  const auto report = nlohmann::json::parse(load.out);
  ASSERT_EQ(report["per_client"].size(), 16u);
  for (const auto& client : report["per_client"]) {
    EXPECT_GT(client["steps"].get<int>(), 0) << client.dump();
    EXPECT_EQ(client["errors"].get<int>(), 0) << client.dump();
  }
  EXPECT_NE(daemon->Log().find("event=session_demoted"), std::string::npos)
      << "no session demoted: the condition of the crash was not met";
  EXPECT_TRUE(daemon->Running());
  const auto stopped = daemon->Stop();
  ASSERT_TRUE(stopped.ok()) << stopped.error().message;
  EXPECT_EQ(*stopped, 0);
}

// A daemon on memq:// (an LCM URL that carries messages only within one LCM instance) can
// serve no client: the client library and far-client say so at once, instead of every step
// waiting out its timeout, and the daemon's log warns at start.
TEST_F(EndToEndTest, ClientRefusesADaemonOnAnInProcessLcmUrlAtOnce) {
  DaemonProcess* daemon = StartDaemon({"--lcm-url", "memq://"});
  ASSERT_NE(daemon, nullptr);
  const auto start = std::chrono::steady_clock::now();
  auto client = client::Client::Connect(TestClientOptions("in-process-url"));
  ASSERT_FALSE(client.ok());
  EXPECT_EQ(client.error().code, ErrorCode::kUnavailable);
  EXPECT_NE(client.error().message.find("memq://"), std::string::npos) << client.error().message;
  EXPECT_NE(client.error().message.find("udpm://"), std::string::npos) << client.error().message;

  TempDir dir;
  const auto path = dir.path() / "soup.json";
  ASSERT_FALSE(WriteAndReadBack(ContactSoup(2), path).empty());
  const ProcessResult run = RunFarClient({"collide", path.string()});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("memq://"), std::string::npos) << run.err;
  // Both answers came well inside one step's timeout (5 s for the library, 60 s for far-client).
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  EXPECT_NE(daemon->Log().find("event=lcm_in_process"), std::string::npos) << daemon->Log();
}

// The client library sends quaternions written with four decimals as the unit quaternions they
// stand for, and refuses one beyond the tolerance at once, naming it, instead of letting the
// next step fail.
TEST_F(EndToEndTest, ClientNormalizesNearlyUnitQuaternionsAndRefusesOthersAtOnce) {
  ASSERT_NE(StartDaemon(), nullptr);
  std::vector<SceneObject> objects = ContactSoup(3);
  auto client = client::Client::Connect(TestClientOptions("quaternions"));
  ASSERT_TRUE(client.ok()) << far::ToString(client.error());
  // Rotations rounded to four decimals, as people write them: no longer of unit norm, but
  // within the tolerance.
  int non_unit = 0;
  for (SceneObject& object : objects) {
    Eigen::Vector4d wxyz = object.X_WO.rotation.coeffs();
    for (int i = 0; i < 4; ++i) wxyz[i] = std::round(wxyz[i] * 1e4) / 1e4;
    object.X_WO.rotation.coeffs() = wxyz;
    non_unit += object.X_WO.rotation.norm() != 1.0;
    ASSERT_TRUE((*client)->AddObject(object.id, object.mesh, object.motion, object.X_WO).ok());
  }
  ASSERT_GT(non_unit, 0);
  auto result = (*client)->Step(SmallRequest(Method::kExact));
  ASSERT_TRUE(result.ok()) << far::ToString(result.error());
  EXPECT_FALSE(result->contacts.empty());

  Pose bad = objects[0].X_WO;
  bad.rotation.coeffs() *= 1.5;
  auto refused = (*client)->SetPose(objects[0].id, bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(refused.error().message.find("set_pose: object " + std::to_string(objects[0].id) +
                                         ": X_WO.rotation_wxyz: not a unit quaternion (norm 1.5"),
            std::string::npos)
      << refused.error().message;
  // Nothing was written: the session goes on.
  auto again = (*client)->Step(SmallRequest(Method::kExact));
  ASSERT_TRUE(again.ok()) << far::ToString(again.error());
  EXPECT_EQ(again->contacts, result->contacts);
}

TEST_F(EndToEndTest, ConcurrentSessionsWithTheSameIdsNeverSeeEachOther) {
  ASSERT_NE(StartDaemon(), nullptr);
  // Same ids (1, 4, 7, ...) and the same region of space: the two scenes interpenetrate.
  const std::vector<SceneObject> a = ContactSoup(21);
  const std::vector<SceneObject> b = ContactSoup(22);
  std::vector<SceneObject> both = a;
  for (SceneObject object : b) {
    object.id += 1000;
    both.push_back(object);
  }
  const auto merged = ReferenceContacts(both);
  const bool cross = std::any_of(merged.begin(), merged.end(), [](const ContactPair& p) {
    return p.object_a < 1000 && p.object_b >= 1000;
  });
  ASSERT_TRUE(cross) << "the two scenes must intersect each other, or a leak could not show";
  std::vector<ContactPair> expected_a = ReferenceContacts(a);
  const std::vector<ContactPair> expected_b = ReferenceContacts(b);
  ASSERT_FALSE(expected_a.empty());
  ASSERT_FALSE(expected_b.empty());

  auto client_a = client::Client::Connect(TestClientOptions("isolation-a"));
  auto client_b = client::Client::Connect(TestClientOptions("isolation-b"));
  ASSERT_TRUE(client_a.ok()) << far::ToString(client_a.error());
  ASSERT_TRUE(client_b.ok()) << far::ToString(client_b.error());
  client::Client& ca = **client_a;
  client::Client& cb = **client_b;

  // Each session: its own id (and its own unnamed segment, reachable by no one else).
  EXPECT_NE(ca.session_id(), cb.session_id());

  Scene scene_a, scene_b;
  scene_a.objects = a;
  scene_b.objects = b;
  ASSERT_TRUE(ca.LoadScene(scene_a).ok());
  ASSERT_TRUE(cb.LoadScene(scene_b).ok());

  // Round 1: both step at once.
  for (int round = 0; round < 2; ++round) {
    SCOPED_TRACE("round " + std::to_string(round));
    auto future_a = ca.StepAsync(SmallRequest());
    auto future_b = cb.StepAsync(SmallRequest());
    ASSERT_EQ(future_a.wait_for(std::chrono::seconds(10)), std::future_status::ready);
    ASSERT_EQ(future_b.wait_for(std::chrono::seconds(10)), std::future_status::ready);
    auto result_a = future_a.get();
    auto result_b = future_b.get();
    ASSERT_TRUE(result_a.ok()) << far::ToString(result_a.error());
    ASSERT_TRUE(result_b.ok()) << far::ToString(result_b.error());
    EXPECT_EQ(result_a->contacts, expected_a) << "A got " << ToString(result_a->contacts);
    EXPECT_EQ(result_b->contacts, expected_b) << "B got " << ToString(result_b->contacts);
    // Round 2: A removes the object with the most contacts; B must not notice.
    if (round == 0) {
      std::map<uint32_t, int> counts;
      for (const auto& p : expected_a) counts[p.object_a]++, counts[p.object_b]++;
      const uint32_t busiest = std::max_element(counts.begin(), counts.end(), [](auto& x, auto& y) {
                                 return x.second < y.second;
                               })->first;
      ASSERT_TRUE(ca.RemoveObject(busiest).ok());
      std::vector<SceneObject> rest;
      for (const auto& o : a) {
        if (o.id != busiest) rest.push_back(o);
      }
      expected_a = ReferenceContacts(rest);
    }
  }
}

TEST_F(EndToEndTest, StatusReportsRendererSessionsLatencyAndErrorKinds) {
  ASSERT_NE(StartDaemon(), nullptr);
  auto session = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "status-probe");
  ASSERT_TRUE(session.ok()) << far::ToString(session.error());
  RawSession& raw = **session;

  // Some steps that work ...
  ASSERT_TRUE(HealthyClientSteps("status-healthy"));
  ASSERT_TRUE(raw.writer().AddObject(1, TriangleRow(1), Motion::kRigid, Pose{}).ok());
  ASSERT_TRUE(raw.SendStep(0, SmallRequest()).ok());
  auto ok_reply = raw.WaitStepReply(0);
  ASSERT_TRUE(ok_reply.has_value());
  ASSERT_EQ(ok_reply->status, 0) << ok_reply->message;

  // ... and errors of three kinds: garbage (parse_error, rejected), a forged tag
  // (permission_denied, rejected) and a NaN pose (invalid_argument).
  // (the first two are dropped unanswered, and counted)
  const std::vector<uint8_t> garbage(40, 0xAB);
  ASSERT_TRUE(raw.PublishRequest(garbage).ok());
  protocol::SessionKey wrong{};
  auto forged = raw.SendStep(1, SmallRequest(), std::nullopt, &wrong);
  ASSERT_TRUE(forged.ok());
  Pose bad;
  bad.translation.x() = std::numeric_limits<double>::quiet_NaN();
  ASSERT_TRUE(raw.writer().SetPose(1, bad).ok());
  ASSERT_TRUE(raw.SendStep(2, SmallRequest()).ok());
  auto nan_reply = raw.WaitStepReply(2);
  ASSERT_TRUE(nan_reply.has_value());
  EXPECT_EQ(nan_reply->status, protocol::ToWireStatus(ErrorCode::kInvalidArgument));

  ProcessResult run;
  json status;
  // (the dropped messages are counted as they arrive: wait until both are)
  WaitUntil(
      [&] {
        run = RunFarClient({"status", "--json"});
        status = json::parse(run.out, nullptr, false);
        return !status.is_discarded() && status.at("rejected_messages_total").get<int64_t>() >= 2;
      },
      std::chrono::seconds(5));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  ASSERT_FALSE(status.is_discarded()) << run.out;
  const std::string renderer = status.at("gl_renderer").get<std::string>();
  EXPECT_FALSE(renderer.empty());
  EXPECT_NE(renderer, "none");
  EXPECT_GE(status.at("steps_total").get<int64_t>(), 2);
  EXPECT_GE(status.at("latency_ms").at("samples").get<int64_t>(), 2);
  EXPECT_GT(status.at("latency_ms").at("p50").get<double>(), 0.0);
  EXPECT_LE(status.at("latency_ms").at("p50").get<double>(),
            status.at("latency_ms").at("p99").get<double>());
  EXPECT_LE(status.at("latency_ms").at("p99").get<double>(),
            status.at("latency_ms").at("max").get<double>());
  // The raw session is open (the healthy client closed its own); it made one good step.
  bool found = false;
  for (const json& s : status.at("sessions")) {
    if (s.at("id").get<int64_t>() != raw.id()) continue;
    found = true;
    EXPECT_EQ(s.at("client").get<std::string>(), "status-probe");
    EXPECT_EQ(s.at("steps").get<int64_t>(), 1);
    EXPECT_EQ(s.at("objects").get<int>(), 1);
  }
  EXPECT_TRUE(found) << run.out;
  const json& errors = status.at("errors_by_kind");
  int64_t sum = 0;
  for (const auto& [kind, count] : errors.items()) sum += count.get<int64_t>();
  for (const char* kind : {"parse_error", "permission_denied", "invalid_argument"}) {
    EXPECT_TRUE(errors.contains(kind) && errors.at(kind).get<int64_t>() >= 1)
        << kind << " in " << errors.dump();
  }
  // Each error, rejected messages included, is counted once.
  EXPECT_EQ(status.at("errors_total").get<int64_t>(), sum) << errors.dump();
  EXPECT_GE(status.at("errors_total").get<int64_t>(), 3);
  EXPECT_GE(status.at("rejected_messages_total").get<int64_t>(), 2);
}

}  // namespace
}  // namespace far::integration
