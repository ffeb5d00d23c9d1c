#include "log_flood.h"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <future>
#include <vector>

#include "far/scenes/scenes.h"

namespace far::study {
namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

LogFloodReport StepFlood(const StudyDaemon& daemon, double seconds) {
  LogFloodReport report;
  auto client = client::Client::Connect(daemon.Options("step-flood", std::chrono::seconds(5)));
  if (!client) {
    report.error = far::ToString(client.error());
    return report;
  }
  const auto objects = scenes::RandomSoup(3, 1, 16, 1.0, 0.3);
  if (auto ok = (*client)->AddObject(objects[0].id, objects[0].mesh, Motion::kRigid); !ok) {
    report.error = far::ToString(ok.error());
    return report;
  }
  StepRequest request;
  request.method = Method::kAabb;
  // The answers are not waited for: their futures are dropped as the loop goes.
  const auto start = Clock::now();
  while (SecondsSince(start) < seconds) {
    for (int i = 0; i < 64; ++i) (void)(*client)->StepAsync(request);
    report.sent += 64;
  }
  report.seconds = SecondsSince(start);
  return report;
}

LogFloodReport OpenFlood(const StudyDaemon& daemon, double seconds) {
  LogFloodReport report;
  client::ClientOptions options = daemon.Options("open-flood");
  options.connect_timeout = std::chrono::milliseconds(0);
  const auto start = Clock::now();
  while (SecondsSince(start) < seconds) {
    ++report.sent;
    auto client = client::Client::Connect(options);
    if (!client) ++report.refused;
  }
  report.seconds = SecondsSince(start);
  return report;
}

std::string LogGrowth::Events() const {
  std::vector<std::pair<int64_t, std::string>> sorted;
  for (const auto& [event, lines] : lines_by_event) sorted.emplace_back(lines, event);
  std::sort(sorted.rbegin(), sorted.rend());
  std::string text;
  for (const auto& [lines, event] : sorted)
    text += (text.empty() ? "" : ", ") + event + " " + std::to_string(lines);
  return text.empty() ? "-" : text;
}

LogGrowth LogGrowthSince(const StudyDaemon& daemon, int64_t from) {
  LogGrowth growth;
  std::ifstream log(daemon.log_path());
  log.seekg(from);
  std::string line;
  while (std::getline(log, line)) {
    growth.bytes += static_cast<int64_t>(line.size()) + 1;
    ++growth.lines;
    const size_t at = line.find("event=");
    if (at == std::string::npos) {
      growth.lines_by_event["(no event)"]++;
      continue;
    }
    const size_t end = line.find(' ', at);
    growth.lines_by_event[line.substr(at + 6, end == std::string::npos ? end : end - at - 6)]++;
  }
  return growth;
}

}  // namespace far::study
