// Record and replay (docs/record-replay.md): far-client record captures a session to one file,
// far-client replay runs it against a fresh daemon and checks the replies; a tampered recording
// is a mismatch; a simulator linking far::client is recorded through FAR_RECORD alone; every
// event of a recording, and of lcm-logger's log of a live session, decodes with the generated
// far_lcm types.
#include <fcntl.h>
#include <signal.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include "daemon_fixture.h"
#include <gtest/gtest.h>

#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/lcm_log.h"
#include "far/protocol/message_validate.h"
#include "far/protocol/recording.h"
#include "far/protocol/shm_reply.h"

namespace far::integration {
namespace {

using RecordReplayTest = DaemonTest;
namespace wire = far_lcm;

int CountLines(const std::string& text, const std::string& needle) {
  int count = 0;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) count += line.find(needle) != std::string::npos;
  return count;
}

// Every event of a log file (the test's own files: a failure is a test failure).
std::vector<protocol::LcmLogEvent> ReadEvents(const std::filesystem::path& path) {
  std::vector<protocol::LcmLogEvent> events;
  auto log = protocol::LcmLogReader::Open(path.string(), protocol::kMaxRecordingEventBytes);
  EXPECT_TRUE(log) << far::ToString(log.error());
  if (!log) return events;
  for (;;) {
    auto event = (*log)->Next();
    EXPECT_TRUE(event) << far::ToString(event.error());
    if (!event || !event->has_value()) return events;
    events.push_back(std::move(**event));
  }
}

void WriteEvents(const std::filesystem::path& path,
                 const std::vector<protocol::LcmLogEvent>& events) {
  std::filesystem::remove(path);
  const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  ASSERT_GE(fd, 0);
  auto log = protocol::LcmLogWriter::FromDescriptor(fd, path.string());
  ASSERT_TRUE(log);
  for (const auto& e : events) ASSERT_TRUE((*log)->Write(e.channel, e.data, e.timestamp_us));
  ASSERT_TRUE((*log)->Flush());
}

// Decodes with the generated type's own decode (no far guard in between): the bytes are
// exactly one T.
template <typename T>
::testing::AssertionResult DecodesAs(const protocol::LcmLogEvent& event, T* out = nullptr) {
  T message;
  const int used = message.decode(event.data.data(), 0, static_cast<int>(event.data.size()));
  if (used != static_cast<int>(event.data.size())) {
    return ::testing::AssertionFailure()
           << event.channel << " event " << event.event_number << ": decode used " << used << " of "
           << event.data.size() << " bytes";
  }
  if (out != nullptr) *out = std::move(message);
  return ::testing::AssertionSuccess();
}

// A small demo scene (a tree, falling leaves, a vase that breaks) with `frames` frames.
std::filesystem::path MakeDemoScene(const TempDir& dir, int frames) {
  const auto path = dir.path() / "demo" / "scene.json";
  const ProcessResult made = RunFarClient({"make-scene", path.string(), "--leaves", "4", "--frames",
                                           std::to_string(frames), "--cells", "2"});
  EXPECT_EQ(made.exit_code, 0) << made.err;
  return path;
}

// Records `far-client play scene args...` into `out`; returns far-client record's output.
ProcessResult RecordPlay(const std::filesystem::path& out, const std::filesystem::path& scene,
                         std::vector<std::string> play_args) {
  std::vector<std::string> args = {"record", out.string(), "play", scene.string()};
  args.insert(args.end(), play_args.begin(), play_args.end());
  return RunFarClient(args);
}

TEST_F(RecordReplayTest, ARecordedPlayReplaysAgainstAFreshDaemonWithMatchingReplies) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const auto scene = MakeDemoScene(dir, 7);
  const auto recording = dir.path() / "play.farrec";
  const ProcessResult recorded =
      RecordPlay(recording, scene, {"--method", "far", "--resolution", "128"});
  ASSERT_EQ(recorded.exit_code, 0) << recorded.out << recorded.err;
  const int steps = CountLines(recorded.out, "round trip");  // play's own lines
  ASSERT_GE(steps, 6) << recorded.out;
  const std::string n = std::to_string(steps);
  EXPECT_NE(recorded.out.find("far-client record: " + n + " steps"), std::string::npos)
      << recorded.out;

  // A fresh daemon (the newest is the one RunFarClient talks to).
  ASSERT_NE(StartDaemon(), nullptr);
  const ProcessResult replayed = RunFarClient({"replay", recording.string()});
  ASSERT_EQ(replayed.exit_code, 0) << replayed.out << replayed.err;
  EXPECT_EQ(CountLines(replayed.out, "  match  "), steps) << replayed.out;
  EXPECT_NE(replayed.out.find("replay: " + n + " steps, every compared reply matches (" + n +
                              " compared"),
            std::string::npos)
      << replayed.out;
  // Steps with contacts were compared, not only empty ones.
  std::smatch m;
  EXPECT_TRUE(std::regex_search(replayed.out, m, std::regex("contacts [1-9][0-9]*,")))
      << replayed.out;
}

TEST_F(RecordReplayTest, EveryEventOfARecordingDecodesWithTheGeneratedTypes) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const auto scene = MakeDemoScene(dir, 3);
  const auto recording = dir.path() / "decode.farrec";
  const ProcessResult recorded = RecordPlay(recording, scene, {"--method", "bvh"});
  ASSERT_EQ(recorded.exit_code, 0) << recorded.out << recorded.err;
  const int steps = CountLines(recorded.out, "round trip");
  ASSERT_GE(steps, 2) << recorded.out;
  const auto events = ReadEvents(recording);
  std::map<std::string, int> by_channel;
  for (const auto& event : events) {
    ++by_channel[event.channel];
    if (event.channel == protocol::kRecordingHeaderChannel) {
      wire::recording_header_t header;
      ASSERT_TRUE(DecodesAs(event, &header));
      EXPECT_EQ(header.client_name, "far-client play");
      EXPECT_EQ(header.format_version, protocol::kRecordingFormatVersion);
      EXPECT_FALSE(header.gl_renderer.empty());
    } else if (event.channel == protocol::kRecordingRingChannel) {
      ASSERT_TRUE(DecodesAs<wire::ring_record_t>(event));
    } else if (event.channel == protocol::kRecordingRequestChannel) {
      wire::step_request_t request;
      ASSERT_TRUE(DecodesAs(event, &request));
      EXPECT_EQ(request.method, "bvh");
      for (uint8_t b : request.auth) ASSERT_EQ(b, 0) << "a recorded request carries its MAC";
    } else if (event.channel == protocol::kRecordingReplyChannel) {
      wire::step_reply_t reply;
      ASSERT_TRUE(DecodesAs(event, &reply));
      EXPECT_EQ(reply.status, 0) << reply.message;
      EXPECT_FALSE(reply.reply_in_shm);
    } else {
      ADD_FAILURE() << "unexpected channel " << event.channel;
    }
  }
  EXPECT_EQ(by_channel["FARREC_HEADER"], 1);
  EXPECT_EQ(by_channel["FARREC_REQUEST"], steps);
  EXPECT_EQ(by_channel["FARREC_REPLY"], steps);
  EXPECT_GT(by_channel["FARREC_RING"], steps);
}

// Removes the first contact of the first recorded reply that has one; returns its step.
int DropOneRecordedContact(std::vector<protocol::LcmLogEvent>& events) {
  int step = 0;
  for (auto& event : events) {
    if (event.channel != protocol::kRecordingReplyChannel) continue;
    wire::step_reply_t reply;
    EXPECT_TRUE(DecodesAs(event, &reply));
    if (reply.num_contacts > 0) {
      reply.contact_object_a.erase(reply.contact_object_a.begin());
      reply.contact_triangle_a.erase(reply.contact_triangle_a.begin());
      reply.contact_object_b.erase(reply.contact_object_b.begin());
      reply.contact_triangle_b.erase(reply.contact_triangle_b.begin());
      --reply.num_contacts;
      event.data = *protocol::EncodeMessage(reply);
      return step;
    }
    ++step;
  }
  return -1;
}

TEST_F(RecordReplayTest, ATamperedReplyOrOtherContentIsAMismatchNamingTheStep) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const auto scene = MakeDemoScene(dir, 7);
  const auto recording = dir.path() / "good.farrec";
  ASSERT_EQ(RecordPlay(recording, scene, {"--method", "bvh"}).exit_code, 0);
  std::vector<protocol::LcmLogEvent> events = ReadEvents(recording);

  // One contact fewer in a recorded reply.
  std::vector<protocol::LcmLogEvent> tampered = events;
  const int step = DropOneRecordedContact(tampered);
  ASSERT_GE(step, 0) << "the demo scene has contacts";
  const auto bad_reply = dir.path() / "bad-reply.farrec";
  WriteEvents(bad_reply, tampered);
  const ProcessResult replayed = RunFarClient({"replay", bad_reply.string()});
  EXPECT_EQ(replayed.exit_code, 1) << replayed.out << replayed.err;
  EXPECT_NE(replayed.out.find("replay: MISMATCH: step " + std::to_string(step) +
                              " (recorded step " + std::to_string(step) + "): contact (object"),
            std::string::npos)
      << replayed.out;
  EXPECT_NE(replayed.out.find("replayed, not recorded"), std::string::npos) << replayed.out;

  // Other content: every recorded set_pose moved far away, so nothing the moving objects
  // touched is touched any more.
  std::vector<protocol::LcmLogEvent> moved = events;
  for (auto& event : moved) {
    if (event.channel != protocol::kRecordingRingChannel) continue;
    wire::ring_record_t record;
    ASSERT_TRUE(DecodesAs(event, &record));
    if (record.type == static_cast<int32_t>(protocol::RecordType::kAddObject) &&
        record.motion != 0) {
      record.X_WO[2] += 1000;
      event.data = *protocol::EncodeMessage(record);
    }
  }
  const auto other = dir.path() / "other-content.farrec";
  WriteEvents(other, moved);
  const ProcessResult differs = RunFarClient({"replay", other.string()});
  EXPECT_EQ(differs.exit_code, 1) << differs.out << differs.err;
  EXPECT_NE(differs.out.find("recorded, not replayed"), std::string::npos) << differs.out;
}

// A play with --geometry records the contact geometry in its replies; a replay compares it,
// and a recorded contact point moved by a micrometre is a mismatch that names the contact.
TEST_F(RecordReplayTest, ContactGeometryIsRecordedAndCompared) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const auto scene = MakeDemoScene(dir, 4);
  const auto recording = dir.path() / "geometry.farrec";
  ASSERT_EQ(RecordPlay(recording, scene, {"--method", "bvh", "--geometry"}).exit_code, 0);
  std::vector<protocol::LcmLogEvent> events = ReadEvents(recording);
  int with_geometry = 0;
  for (auto& event : events) {
    if (event.channel != protocol::kRecordingReplyChannel) continue;
    wire::step_reply_t reply;
    ASSERT_TRUE(DecodesAs(event, &reply));
    if (reply.num_contact_geometry == 0) continue;
    EXPECT_EQ(reply.num_contact_geometry, reply.num_contacts);
    if (with_geometry++ == 0) {
      reply.contact_points[0] += 1e-6;
      event.data = *protocol::EncodeMessage(reply);
    }
  }
  ASSERT_GT(with_geometry, 0) << "the demo scene has contacts";
  ASSERT_EQ(RunFarClient({"replay", recording.string()}).exit_code, 0);
  const auto moved = dir.path() / "moved-point.farrec";
  WriteEvents(moved, events);
  const ProcessResult replayed = RunFarClient({"replay", moved.string()});
  EXPECT_EQ(replayed.exit_code, 1) << replayed.out << replayed.err;
  EXPECT_NE(replayed.out.find("contact geometry of (object"), std::string::npos) << replayed.out;
}

TEST_F(RecordReplayTest, AnUnreadableRecordingIsAClearErrorNotAReplay) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const auto scene = MakeDemoScene(dir, 2);
  const auto recording = dir.path() / "whole.farrec";
  ASSERT_EQ(RecordPlay(recording, scene, {"--method", "bvh"}).exit_code, 0);
  const auto size = std::filesystem::file_size(recording);
  std::filesystem::resize_file(recording, size - 5);
  const ProcessResult cut = RunFarClient({"replay", recording.string()});
  EXPECT_EQ(cut.exit_code, 2) << cut.out << cut.err;
  EXPECT_NE(cut.err.find("truncated"), std::string::npos) << cut.err;
  EXPECT_EQ(cut.out, "") << "nothing was replayed";

  const ProcessResult scene_file = RunFarClient({"replay", scene.string()});
  EXPECT_EQ(scene_file.exit_code, 2);
  EXPECT_NE(scene_file.err.find("not an LCM log file"), std::string::npos) << scene_file.err;
}

TEST_F(RecordReplayTest, ASimulatorLinkingTheClientLibraryIsRecordedThroughFarRecord) {
  DaemonProcess* daemon = StartDaemon();
  ASSERT_NE(daemon, nullptr);
  TempDir dir;
  const auto recording = dir.path() / "sim.farrec";
  const ProcessResult recorded = RunFarClient({"record", recording.string(), "--", SelfPath(),
                                               "--far-simulator", daemon->socket_path(), "6"});
  ASSERT_EQ(recorded.exit_code, 0) << recorded.out << recorded.err;
  EXPECT_EQ(CountLines(recorded.out, "distance pairs"), 6) << recorded.out;
  EXPECT_NE(recorded.out.find("6 steps"), std::string::npos) << recorded.out;
  // Its replies came through the reply ring (shared memory); the recording holds them whole.
  size_t largest_reply = 0;
  for (const auto& event : ReadEvents(recording)) {
    if (event.channel == protocol::kRecordingReplyChannel)
      largest_reply = std::max(largest_reply, event.data.size());
  }
  EXPECT_GT(largest_reply, protocol::kShmReplyThresholdBytes);

  ASSERT_NE(StartDaemon(), nullptr);
  const ProcessResult replayed = RunFarClient({"replay", recording.string()});
  ASSERT_EQ(replayed.exit_code, 0) << replayed.out << replayed.err;
  EXPECT_NE(replayed.out.find("recorded by 'test-simulator'"), std::string::npos) << replayed.out;
  EXPECT_EQ(CountLines(replayed.out, "  match  "), 6) << replayed.out;
}

TEST_F(RecordReplayTest, SessionsRecordToTheirOwnFilesAndNeverOverwrite) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const std::string path = (dir.path() / "lib.farrec").string();
  client::ClientOptions options = TestClientOptions("recorded");
  options.record_path = path;
  auto first = client::Client::Connect(options);
  ASSERT_TRUE(first) << far::ToString(first.error());
  auto second = client::Client::Connect(options);
  ASSERT_TRUE(second) << far::ToString(second.error());
  EXPECT_EQ((*first)->recording_path(), path);
  EXPECT_EQ((*second)->recording_path(), (dir.path() / "lib.2.farrec").string());
  options.record_path = std::string();  // "" records nothing, whatever FAR_RECORD says
  auto none = client::Client::Connect(options);
  ASSERT_TRUE(none);
  EXPECT_EQ((*none)->recording_path(), "");

  options.record_path = (dir.path() / "no-such-dir" / "x.farrec").string();
  auto refused = client::Client::Connect(options);
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().code, ErrorCode::kIoError);
  EXPECT_NE(refused.error().message.find("no-such-dir"), std::string::npos);
}

// What lcm-logger captures of a live session decodes with the generated types: requests as
// step_request_t (signed: their MAC is there), replies as sealed_t (their content is private to
// the session by design, so a bus log cannot be replayed; a far recording can).
TEST_F(RecordReplayTest, LcmLoggerLogOfALiveSessionDecodesWithTheGeneratedTypes) {
  ASSERT_NE(StartDaemon(), nullptr);
  TempDir dir;
  const auto scene = MakeDemoScene(dir, 3);
  const auto log_path = dir.path() / "bus.lcmlog";
  auto logger = ChildProcess::Spawn({"/usr/bin/lcm-logger", "--lcm-url=" + TestLcmUrl(),
                                     "--flush-interval=10", "-f", log_path.string()});
  ASSERT_TRUE(logger) << far::ToString(logger.error());
  ASSERT_TRUE(
      WaitUntil([&] { return std::filesystem::exists(log_path); }, std::chrono::seconds(5)));
  const ProcessResult played = RunFarClient({"play", scene.string(), "--method", "bvh"});
  ASSERT_EQ(played.exit_code, 0) << played.err;
  const int steps = CountLines(played.out, "round trip");
  ASSERT_GE(steps, 2) << played.out;
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  kill((*logger)->pid(), SIGINT);
  EXPECT_TRUE((*logger)->Wait(std::chrono::seconds(5)));

  int probes = 0, replies = 0;
  std::set<int64_t> requested;  // step ids: a step asked for again is one step
  for (const auto& event : ReadEvents(log_path)) {
    if (event.channel == "LCM_SELF_TEST") continue;  // LCM's own, when the logger starts
    const bool is_request = event.channel.ends_with("_REQ");
    ASSERT_TRUE(is_request || event.channel.ends_with("_REPLY")) << event.channel;
    if (is_request) {
      wire::step_request_t request;
      ASSERT_TRUE(DecodesAs(event, &request));
      EXPECT_NE(std::count(std::begin(request.auth), std::end(request.auth), 0), 32);
      // The client's probe at open (docs/protocol.md, "Lost datagrams"), then the steps.
      if (protocol::IsProbe(request)) {
        ++probes;
        continue;
      }
      EXPECT_TRUE(protocol::ValidateStepRequest(request));
      requested.insert(request.step_id);
    } else {
      wire::sealed_t sealed;
      ASSERT_TRUE(DecodesAs(event, &sealed));
      EXPECT_GT(sealed.box_bytes, 16);
      ++replies;
    }
  }
  EXPECT_GE(probes, 1);
  EXPECT_EQ(static_cast<int>(requested.size()), steps);
  EXPECT_GE(replies, steps);  // the replies and the step_status_t messages before them
}

}  // namespace
}  // namespace far::integration
