#pragma once

// Finding a daemon on this machine without knowing its name: what `far-client --daemon auto`
// and `far-client status --all` do, and Client::Connect with ClientOptions::daemon "auto"
// (docs/cluster.md, "Finding a daemon"). A node of a cluster runs one daemon per GPU; a job
// scheduled onto it knows which GPUs it was given, not what the daemons are called.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "far/client/client.h"

namespace far::client {

/// ClientOptions::daemon's value that makes Connect and Status choose a daemon (RankDaemons).
/// No daemon may take this name.
inline constexpr std::string_view kAutoDaemon = "auto";

/// The environment variable a scheduler (or a job script) sets to name the daemon of every
/// client of the job: a daemon name or "auto". It applies to options that name no daemon and
/// give no socket (ClientOptions{}): WithDaemonFromEnvironment.
inline constexpr const char* kDaemonEnvironmentVariable = "FAR_DAEMON";

/// `options` with a daemon name: when it names none, $FAR_DAEMON's (when set and no
/// socket_path is given), else kDefaultDaemonName.
ClientOptions WithDaemonFromEnvironment(ClientOptions options);

/// A daemon socket found on this machine, and what its daemon answered (or why it did not: a
/// socket left by a daemon that died, one that fails the trust check, ...).
struct FoundDaemon {
  std::string socket_path;
  std::optional<DaemonStatus> status;
  std::string error;  ///< why there is no status
};

/// Every daemon socket on this machine: each "*.sock" socket in the socket directories
/// ($FAR_SOCKET_DIR alone when set; else /run/far, $XDG_RUNTIME_DIR/far, /tmp/far-<uid> or
/// $HOME/.far/run-<host>, those that exist), each asked for its status once (no waiting for
/// daemons that are not there yet), sorted by path.
std::vector<FoundDaemon> FindDaemons(const ClientOptions& options = {});

/// The GPUs this process' job was given, as its scheduler names them: the first of $FAR_GPUS,
/// $SLURM_STEP_GPUS, $SLURM_JOB_GPUS and $NVIDIA_VISIBLE_DEVICES that is set, split at commas
/// ("0,2" -> {"0", "2"}). NVIDIA's "all", "none" and "void" name no particular GPU: empty.
/// $CUDA_VISIBLE_DEVICES is not read: its numbers count the devices visible to the process,
/// not the machine's.
std::vector<std::string> JobGpus();

/// The daemons of `found` that auto may choose, best first, as indices into `found`: those
/// that answered their status; when some of them serve one of `job_gpus` (DaemonStatus::
/// gpu_names), only those, so that no client lands on another GPU's daemon; the least loaded
/// first (open sessions as a share of max_sessions), ties spread over the processes of a job
/// by `spread` (the process id), so that clients starting together do not all pick the first.
std::vector<size_t> RankDaemons(const std::vector<FoundDaemon>& found,
                                const std::vector<std::string>& job_gpus, uint64_t spread);

}  // namespace far::client
