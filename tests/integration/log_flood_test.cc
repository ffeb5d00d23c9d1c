// What a client's floods add to the daemon's log (issue 41): every line a client can cause
// goes through the daemon's log limiter (a few lines a second per user and kind, and a
// summary with the count of the rest), so a flood of busy steps and refused opens adds a few
// hundred bytes a second, where it used to add a line per request (about 1 MB/s).
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <future>
#include <regex>
#include <thread>

#include "daemon_fixture.h"
#include "integration_scenes.h"
#include "raw_session.h"
#include <gtest/gtest.h>

#include "far/client/client.h"

namespace far::integration {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

int64_t FileBytes(const std::filesystem::path& path) {
  struct stat info {};
  return stat(path.c_str(), &info) == 0 ? static_cast<int64_t>(info.st_size) : -1;
}

// The sum of count= over the log_suppressed lines of `kind` for this process's uid.
int64_t Suppressed(const std::string& log, const std::string& kind) {
  const std::regex line("event=log_suppressed kind=" + kind + " user=" + std::to_string(geteuid()) +
                        " count=([0-9]+)");
  int64_t total = 0;
  for (std::sregex_iterator it(log.begin(), log.end(), line), end; it != end; ++it)
    total += std::stoll((*it)[1]);
  return total;
}

// The lines of `log` that contain `text`.
int64_t Lines(const std::string& log, const std::string& text) {
  int64_t lines = 0;
  for (size_t at = log.find(text); at != std::string::npos; at = log.find(text, at + 1)) ++lines;
  return lines;
}

using LogFloodTest = DaemonTest;

TEST_F(LogFloodTest, BusyStepsAndRefusedOpensAddAFewHundredBytesASecond) {
  // One session per user: every other open of this user is refused at once.
  DaemonProcess* daemon = StartDaemon({"--max-sessions-per-user", "1"});
  ASSERT_NE(daemon, nullptr);
  auto raw = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "step-flood");
  ASSERT_TRUE(raw.ok()) << far::ToString(raw.error());
  ASSERT_TRUE((*raw)->writer().AddObject(1, TriangleRow(4), Motion::kRigid, Pose{}).ok());
  constexpr auto kFlood = 7s, kBursts = 2s;
  const int64_t start_bytes = FileBytes(daemon->log_path());
  const auto start = Clock::now();
  // The session sends step requests without waiting (all but a few are busy); its user opens
  // sessions back to back (each refused).
  std::atomic<bool> stop{false};
  auto steps = std::async(std::launch::async, [&] {
    int64_t sent = 0;
    while (!stop) sent += (*raw)->SendStep(sent, SmallRequest(Method::kAabb)).ok();
    return sent;
  });
  auto opens = std::async(std::launch::async, [&] {
    int64_t refused = 0;
    while (!stop) refused += !client::Client::Connect(TestClientOptions("open-flood")).ok();
    return refused;
  });
  // Every kind's burst is spent in the first seconds; from then on, a line a second per kind.
  std::this_thread::sleep_until(start + kBursts);
  const int64_t after_bursts = FileBytes(daemon->log_path());
  std::this_thread::sleep_until(start + kFlood);
  const int64_t end_bytes = FileBytes(daemon->log_path());
  stop = true;
  const int64_t sent = steps.get(), refused = opens.get();
  const double steady_s = std::chrono::duration<double>(kFlood - kBursts).count();

  EXPECT_GT(sent, 2000) << "the step flood did not happen";
  EXPECT_GT(refused, 200) << "the open flood did not happen";
  const double steady_rate = (end_bytes - after_bursts) / steady_s;
  EXPECT_LT(steady_rate, 2048) << "bytes per second once the bursts were spent";
  EXPECT_LT(end_bytes - start_bytes, 32 * 1024) << "bytes in all over " << kFlood.count() << " s";
  RecordProperty("log_bytes_per_second_steady", static_cast<int>(steady_rate));
  // Nothing is lost from the count: at shutdown, what was held back is summarized.
  StopDaemon(*daemon);
  const std::string log = daemon->Log();
  EXPECT_GT(Suppressed(log, "step_busy"), 1000);
  EXPECT_EQ(Lines(log, "event=open_refused uid=" + std::to_string(geteuid()) + " ") +
                Suppressed(log, "open_refused"),
            refused)
      << "every refused open is logged or counted";
}

}  // namespace
}  // namespace far::integration
