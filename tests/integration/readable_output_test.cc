// What far-client tells a person: play --contacts lists each step's contacts by object pair,
// named as the scene names them, with the counts the daemon's contacts give; a frame that breaks
// an object says so; each step names the method that answered; load --seconds runs for the time
// it is given; status says whose sessions it lists, and "none".
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <map>
#include <sstream>

#include "daemon_fixture.h"
#include "integration_scenes.h"
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "far/client/client.h"
#include "far/io/scene_io.h"

namespace far::integration {
namespace {

using nlohmann::json;
using ReadableOutputTest = DaemonTest;

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST_F(ReadableOutputTest, PlayContactsNamesEveryObjectPairWithItsTrianglePairCount) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  Scene scene;
  scene.objects = ContactSoup(3);
  for (SceneObject& object : scene.objects) object.name = "piece-" + std::to_string(object.id);
  scene.objects.back().name.clear();  // an unnamed object is named by its id
  const uint32_t unnamed = scene.objects.back().id;
  const auto path = dir.path() / "named.json";
  ASSERT_TRUE(WriteScene(scene, path).ok());
  auto read = ReadScene(path);
  ASSERT_TRUE(read.ok()) << far::ToString(read.error());
  const std::vector<ContactPair> contacts = ReferenceContacts(read->objects);
  ASSERT_GE(contacts.size(), 3u);
  // The lines the contacts call for, counted from the brute-force reference.
  std::map<std::pair<uint32_t, uint32_t>, size_t> counts;
  for (const ContactPair& c : contacts) ++counts[{c.object_a, c.object_b}];
  const auto label = [unnamed](uint32_t id) {
    return id == unnamed ? "object " + std::to_string(id) : "piece-" + std::to_string(id);
  };

  const ProcessResult played =
      RunFarClient({"play", path.string(), "--method", "exact", "--contacts"});
  ASSERT_EQ(played.exit_code, 0) << played.err;
  const std::vector<std::string> lines = Lines(played.out);
  // The step line, a line per touching object pair, the certificate (exact: one line).
  ASSERT_EQ(lines.size(), 1 + counts.size() + 1) << played.out;
  for (const auto& [pair, count] : counts) {
    const std::string expected = "      " + label(pair.first) + " touches " + label(pair.second) +
                                 " (" + std::to_string(count) + " triangle pair" +
                                 (count == 1 ? "" : "s") + ")";
    EXPECT_NE(std::find(lines.begin(), lines.end(), expected), lines.end())
        << "missing '" << expected << "' in\n"
        << played.out;
  }

  // --json keeps the machine format: the same, as fields.
  const ProcessResult as_json =
      RunFarClient({"play", path.string(), "--method", "exact", "--contacts", "--json"});
  ASSERT_EQ(as_json.exit_code, 0) << as_json.err;
  const json step = json::parse(as_json.out);
  ASSERT_EQ(step.at("object_contacts").size(), counts.size()) << as_json.out;
  size_t total = 0;
  for (const json& pair : step.at("object_contacts")) {
    const auto a = pair.at("object_a").get<uint32_t>(), b = pair.at("object_b").get<uint32_t>();
    EXPECT_EQ(pair.at("triangle_pairs").get<size_t>(), counts.at({std::min(a, b), std::max(a, b)}));
    EXPECT_EQ(pair.at("name_a").get<std::string>(), a == unnamed ? "" : label(a));
    total += pair.at("triangle_pairs").get<size_t>();
  }
  EXPECT_EQ(total, contacts.size());
}

TEST_F(ReadableOutputTest, PlaySaysWhenTheDemoVaseBreaks) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const auto path = dir.path() / "demo" / "scene.json";
  const ProcessResult made =
      RunFarClient({"make-scene", path.string(), "--leaves", "4", "--frames", "7", "--cells", "2"});
  ASSERT_EQ(made.exit_code, 0) << made.err;
  auto scene = ReadScene(path);
  ASSERT_TRUE(scene.ok()) << far::ToString(scene.error());
  // The generator breaks the vase at frame 7 / 3 = 2: frames[1] removes it and adds 4 pieces.
  ASSERT_EQ(scene->frames[1].removals.size(), 1u);
  ASSERT_EQ(scene->frames[1].additions.size(), 4u);

  const ProcessResult played = RunFarClient({"play", path.string(), "--resolution", "128"});
  ASSERT_EQ(played.exit_code, 0) << played.err;
  const std::vector<std::string> lines = Lines(played.out);
  const std::string expected =
      "frame   2: vase breaks into 4 fragments: vase-fragment-1, vase-fragment-2, "
      "vase-fragment-3, vase-fragment-4";
  const auto at = std::find(lines.begin(), lines.end(), expected);
  ASSERT_NE(at, lines.end()) << played.out;
  // Said just before the step that first sees the fragments, and only once.
  ASSERT_NE(at + 1, lines.end());
  EXPECT_EQ((at + 1)->rfind("step   2 ", 0), 0u) << *(at + 1);
  EXPECT_EQ(
      std::count_if(lines.begin(), lines.end(),
                    [](const std::string& l) { return l.find("breaks") != std::string::npos; }),
      1)
      << played.out;
}

// play prints the certificate when the configuration changes, and every step with
// --certificate: the method's guarantee, then one line per GPU level.
TEST_F(ReadableOutputTest, PlayPrintsTheCertificateOfItsAnswers) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const auto path = dir.path() / "demo" / "scene.json";
  ASSERT_EQ(RunFarClient({"make-scene", path.string(), "--leaves", "4", "--frames", "3"}).exit_code,
            0);
  auto count = [](const std::string& out, const std::string& text) {
    const std::vector<std::string> lines = Lines(out);
    return std::count_if(lines.begin(), lines.end(), [&](const std::string& line) {
      return line.find(text) != std::string::npos;
    });
  };
  const ProcessResult once =
      RunFarClient({"play", path.string(), "--method", "far", "--resolution", "128"});
  ASSERT_EQ(once.exit_code, 0) << once.err;
  EXPECT_EQ(count(once.out, "certificate: guaranteed: "), 1) << once.out;
  EXPECT_EQ(count(once.out, "  object     3 views at 128 px: r "), 1) << once.out;
  const ProcessResult every = RunFarClient(
      {"play", path.string(), "--method", "cullide", "--resolution", "128", "--certificate"});
  ASSERT_EQ(every.exit_code, 0) << every.err;
  EXPECT_EQ(count(every.out, "certificate: not guaranteed: "), 3) << every.out;
  EXPECT_GE(count(every.out, "no offset (r 0)"), 3) << every.out;
}

// Every step line names the configuration that answered it; under auto, why auto chose it
// comes with the certificate when the choice changes (deploy/run-demo.sh shows both).
TEST_F(ReadableOutputTest, PlayNamesTheMethodThatAnsweredAndWhyAutoChoseIt) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const auto path = dir.path() / "demo" / "scene.json";
  ASSERT_EQ(RunFarClient({"make-scene", path.string(), "--leaves", "4", "--frames", "3"}).exit_code,
            0);
  const ProcessResult aabb = RunFarClient({"play", path.string(), "--method", "aabb"});
  ASSERT_EQ(aabb.exit_code, 0) << aabb.err;
  int steps = 0;
  for (const std::string& line : Lines(aabb.out)) {
    if (line.rfind("step ", 0) != 0) continue;
    ++steps;
    EXPECT_TRUE(line.ends_with("  method aabb")) << line;
  }
  EXPECT_EQ(steps, 3) << aabb.out;
  EXPECT_EQ(aabb.out.find("auto: "), std::string::npos) << aabb.out;

  const ProcessResult chosen = RunFarClient({"play", path.string(), "--resolution", "128"});
  ASSERT_EQ(chosen.exit_code, 0) << chosen.err;
  const std::vector<std::string> lines = Lines(chosen.out);
  EXPECT_GE(std::count_if(lines.begin(), lines.end(),
                          [](const std::string& l) { return l.rfind("auto: ", 0) == 0; }),
            1)
      << chosen.out;
  for (const std::string& line : lines) {
    if (line.rfind("step ", 0) == 0) {
      EXPECT_NE(line.find("  method "), std::string::npos) << line;
    }
  }
}

// status ends on whose sessions it lists and "none" when there are none (not on a bare
// "yours:"); an open session is listed under that line.
TEST_F(ReadableOutputTest, StatusSaysNoneWithoutSessionsAndListsAnOpenOne) {
  ASSERT_NE(StartDaemon(), nullptr);
  const std::string whose = getuid() == 0 ? "every user's" : "yours";
  const auto sessions_line = [](const std::vector<std::string>& lines) {
    return std::find_if(lines.begin(), lines.end(),
                        [](const std::string& l) { return l.rfind("sessions: ", 0) == 0; });
  };
  const ProcessResult idle = RunFarClient({"status"});
  ASSERT_EQ(idle.exit_code, 0) << idle.err;
  const std::vector<std::string> idle_lines = Lines(idle.out);
  const auto idle_at = sessions_line(idle_lines);
  ASSERT_NE(idle_at, idle_lines.end()) << idle.out;
  EXPECT_TRUE(idle_at->ends_with("; " + whose + ": none")) << *idle_at;
  EXPECT_EQ(idle_at + 1, idle_lines.end()) << idle.out;

  auto client = client::Client::Connect(TestClientOptions("status-lister"));
  ASSERT_TRUE(client.ok()) << far::ToString(client.error());
  const ProcessResult busy = RunFarClient({"status"});
  ASSERT_EQ(busy.exit_code, 0) << busy.err;
  const std::vector<std::string> busy_lines = Lines(busy.out);
  const auto busy_at = sessions_line(busy_lines);
  ASSERT_NE(busy_at, busy_lines.end()) << busy.out;
  EXPECT_TRUE(busy_at->ends_with("; " + whose + ":")) << *busy_at;
  ASSERT_NE(busy_at + 1, busy_lines.end()) << busy.out;
  EXPECT_NE((busy_at + 1)->find("status-lister"), std::string::npos) << busy.out;
}

// Each line reaches a pipe when it is printed (deploy/run-demo.sh shows several clients' lines
// as they happen), not when far-client ends: with the daemon paused after the first line, play
// is still waiting for its second step, and its first line has already arrived.
TEST_F(ReadableOutputTest, PlayLinesReachAPipeAsTheyArePrinted) {
  DaemonProcess* daemon = StartDaemon();
  ASSERT_NE(daemon, nullptr);
  TempDir dir;
  const auto path = dir.path() / "demo" / "scene.json";
  ASSERT_EQ(RunFarClient({"make-scene", path.string(), "--leaves", "4", "--frames", "3"}).exit_code,
            0);
  auto child = ChildProcess::Spawn({FAR_CLIENT_PATH, "--socket", CurrentSocketPath(), "play",
                                    path.string(), "--method", "far", "--resolution", "1024"});
  ASSERT_TRUE(child.ok()) << far::ToString(child.error());
  const std::optional<std::string> first = (*child)->ReadLine(std::chrono::seconds(30));
  ASSERT_TRUE(first.has_value());
  ::kill(daemon->pid(), SIGSTOP);  // steps 1 and 2 now wait
  EXPECT_EQ(first->rfind("step   0 ", 0), 0u) << *first;
  const std::optional<int> exited = (*child)->Wait(std::chrono::milliseconds(300));
  ::kill(daemon->pid(), SIGCONT);
  EXPECT_FALSE(exited.has_value())
      << "far-client had ended when its first line arrived: its output was held back";
  int steps = 1;
  while (auto line = (*child)->ReadLine(std::chrono::seconds(30)))
    steps += line->rfind("step", 0) == 0;
  EXPECT_EQ(steps, 3);
  EXPECT_EQ((*child)->Wait(std::chrono::seconds(30)), 0);
}

// --seconds alone runs until the time is up: no hidden step count stops it first.
TEST_F(ReadableOutputTest, LoadWithSecondsAloneRunsForThatLong) {
  ASSERT_NE(StartDaemon(), nullptr);
  const ProcessResult load = RunFarClient({"load", "--clients", "1", "--seconds", "3", "--method",
                                           "aabb", "--resolution", "64", "--json"});
  ASSERT_EQ(load.exit_code, 0) << load.out << load.err;
  const json report = json::parse(load.out);
  EXPECT_GE(report["overall"]["seconds"].get<double>(), 3.0) << report.dump();
  // aabb on 24 small objects takes about a millisecond: far more than the old 100 steps.
  EXPECT_GT(report["per_client"][0]["steps"].get<int>(), 100) << report.dump();
  // --steps 0 without --seconds would never end: refused.
  const ProcessResult endless = RunFarClient({"load", "--steps", "0"});
  EXPECT_EQ(endless.exit_code, 1);
  EXPECT_NE(endless.err.find("--steps 0 (no limit) needs --seconds"), std::string::npos)
      << endless.err;
}

}  // namespace
}  // namespace far::integration
