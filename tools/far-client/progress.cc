#include "progress.h"

#include <unistd.h>

#include <cstdio>
#include <mutex>

namespace far::cli {
namespace {

bool g_shown = false;  // a progress line is on the terminal
std::mutex g_mutex;

}  // namespace

client::ProgressCallback ProgressLine(const std::string& label) {
  if (!isatty(STDOUT_FILENO)) return {};
  return [label](const client::StepProgress& progress) {
    std::lock_guard lock(g_mutex);
    std::string what = progress.state;
    if (progress.state == "queued" && progress.queue_position > 0)
      what += " (" + std::to_string(progress.queue_position) + " ahead)";
    if (progress.stage) what = far::ToString(*progress.stage);
    std::fprintf(stderr, "\r\033[K%s: %s, %.1f s", label.c_str(), what.c_str(),
                 progress.elapsed_ms / 1000.0);
    std::fflush(stderr);
    g_shown = true;
  };
}

void EndProgress() {
  std::lock_guard lock(g_mutex);
  if (!g_shown) return;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
  g_shown = false;
}

}  // namespace far::cli
