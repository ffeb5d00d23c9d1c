#include "far/client/discovery.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

#include "daemon_connection.h"

#include "far/base/gpu_identity.h"
#include "far/protocol/channels.h"

namespace far::client {
namespace {

std::vector<std::string> SplitCommas(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, ',');) {
    part.erase(0, part.find_first_not_of(" \t"));
    part.erase(part.find_last_not_of(" \t") + 1);
    if (!part.empty()) parts.push_back(part);
  }
  return parts;
}

bool ServesOneOf(const DaemonStatus& status, const std::vector<std::string>& gpus) {
  return std::any_of(gpus.begin(), gpus.end(),
                     [&](const std::string& gpu) { return NamesGpu(gpu, status.gpu_names); });
}

double Load(const DaemonStatus& status) {
  return status.max_sessions > 0 ? double(status.sessions_open) / status.max_sessions : 1.0;
}

}  // namespace

ClientOptions WithDaemonFromEnvironment(ClientOptions options) {
  if (!options.daemon.empty()) return options;
  const char* named = std::getenv(kDaemonEnvironmentVariable);
  options.daemon = named != nullptr && *named != '\0' && options.socket_path.empty()
                       ? named
                       : std::string(kDefaultDaemonName);
  return options;
}

std::vector<FoundDaemon> FindDaemons(const ClientOptions& options) {
  namespace fs = std::filesystem;
  std::set<std::string> paths;
  for (const std::string& dir : protocol::SocketDirectories()) {
    std::error_code error;
    for (fs::directory_iterator it(dir, error), end; !error && it != end; it.increment(error)) {
      const fs::path& path = it->path();
      struct stat info {};
      if (path.extension() == ".sock" && lstat(path.c_str(), &info) == 0 &&
          S_ISSOCK(info.st_mode)) {
        paths.insert(path.string());
      }
    }
  }
  std::vector<FoundDaemon> found;
  for (const std::string& path : paths) {
    ClientOptions one = options;
    one.socket_path = path;
    one.connect_timeout = std::chrono::milliseconds(0);  // there now, or not a daemon
    FoundDaemon daemon{path, std::nullopt, ""};
    if (auto status = Client::Status(one)) {
      daemon.status = std::move(*status);
    } else {
      daemon.error = status.error().message;
    }
    found.push_back(std::move(daemon));
  }
  return found;
}

std::vector<std::string> JobGpus() {
  for (const char* variable :
       {"FAR_GPUS", "SLURM_STEP_GPUS", "SLURM_JOB_GPUS", "NVIDIA_VISIBLE_DEVICES"}) {
    const char* value = std::getenv(variable);
    if (value == nullptr) continue;
    const std::string text = value;
    if (text == "all" || text == "none" || text == "void") return {};
    return SplitCommas(text);
  }
  return {};
}

std::vector<size_t> RankDaemons(const std::vector<FoundDaemon>& found,
                                const std::vector<std::string>& job_gpus, uint64_t spread) {
  std::vector<size_t> answered, for_gpu;
  for (size_t i = 0; i < found.size(); ++i) {
    if (!found[i].status) continue;
    answered.push_back(i);
    if (ServesOneOf(*found[i].status, job_gpus)) for_gpu.push_back(i);
  }
  std::vector<size_t> ranked = for_gpu.empty() ? answered : for_gpu;
  std::sort(ranked.begin(), ranked.end(), [&](size_t a, size_t b) {
    return std::make_tuple(Load(*found[a].status), found[a].socket_path) <
           std::make_tuple(Load(*found[b].status), found[b].socket_path);
  });
  // The daemons as loaded as the least loaded: each process starts at its own (spread % n).
  size_t tied = 0;
  while (tied < ranked.size() &&
         Load(*found[ranked[tied]].status) == Load(*found[ranked[0]].status))
    ++tied;
  if (tied > 1)
    std::rotate(ranked.begin(), ranked.begin() + static_cast<ptrdiff_t>(spread % tied),
                ranked.begin() + static_cast<ptrdiff_t>(tied));
  return ranked;
}

}  // namespace far::client

namespace far::client::internal {

Result<std::vector<ClientOptions>> ChooseDaemons(const ClientOptions& options) {
  const std::vector<std::string> gpus = JobGpus();
  const auto start = std::chrono::steady_clock::now();
  auto pause = std::chrono::milliseconds(20);
  for (;;) {
    const std::vector<FoundDaemon> found = FindDaemons(options);
    std::vector<ClientOptions> chosen;
    for (size_t i : RankDaemons(found, gpus, static_cast<uint64_t>(getpid()))) {
      ClientOptions one = options;
      one.socket_path = found[i].socket_path;
      one.daemon = found[i].status->daemon_name;
      chosen.push_back(std::move(one));
    }
    if (!chosen.empty()) return chosen;
    // None yet: daemons may be starting (a job starts them beside its simulators).
    const auto waited = std::chrono::steady_clock::now() - start;
    if (waited + pause > options.connect_timeout) {
      std::string dirs, seen;
      for (const std::string& dir : protocol::SocketDirectories())
        dirs += (dirs.empty() ? "" : ", ") + dir;
      for (const FoundDaemon& daemon : found)
        seen += "; " + daemon.socket_path + ": " + daemon.error;
      return MakeError(ErrorCode::kUnavailable,
                       "--daemon auto: no far-daemon answers on this machine (sockets *.sock in " +
                           dirs + seen + "). Start one, or name it with --daemon / --socket");
    }
    std::this_thread::sleep_for(pause);
    pause = std::min(pause * 2, std::chrono::milliseconds(200));
  }
}

}  // namespace far::client::internal
