// far-client: probe a running far-daemon, run scene files through it, load-test it, record a
// session and replay it. Pictures of a step are far-snapshot's (tools/far-snapshot), so that
// far-client links no GL, EGL or FCL.
// Usage and examples: far-client --help, far-client <command> --help, README.md.
// Each command lives in its own file.
#include <cstdio>
#include <string>
#include <vector>

#include "cli_common.h"
#include "commands.h"

int main(int argc, char** argv) {
  // Every line reaches a pipe as it is printed (deploy/run-demo.sh prefixes each client's lines
  // as they come), not in one burst when the buffer fills or the command ends.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  far::cli::SetProgramName("far-client");
  return far::cli::RunGuarded([&] {
    CLI::App app{"far-client: probe a far-daemon, run scene files through it, load-test it",
                 "far-client"};
    app.require_subcommand(1);
    app.footer("Pictures of a step (PCS yellow, contacts red): far-snapshot --help.");
    app.fallthrough();  // the global flags may also come after the command
    far::cli::GlobalFlags global;
    std::vector<std::string> record_command;  // far-client record FILE <these words>
    app.add_option("--daemon", global.options.daemon,
                   "the daemon's name (far-daemon --name): its socket is <dir>/<name>.sock; "
                   "'auto': the daemon of the job's GPU ($FAR_GPUS, $SLURM_STEP_GPUS, "
                   "$SLURM_JOB_GPUS, $NVIDIA_VISIBLE_DEVICES), else the least loaded on this "
                   "machine (default: $FAR_DAEMON, else far)");
    app.add_option("--socket", global.options.socket_path,
                   "the daemon's socket path, when not the default for its name");
    app.add_option("--lcm-url", global.options.lcm_url,
                   "LCM URL of the session channels (default: the one the daemon names)");
    app.add_option("--connect-timeout", global.connect_timeout,
                   "how long to look for a daemon that is not (yet) there before saying so "
                   "(500ms, 2s, 1min)")
        ->capture_default_str();

    const std::vector<far::cli::Command> commands = {
        far::cli::AddPingCommand(app, global),
        far::cli::AddStatusCommand(app, global),
        far::cli::AddCollideCommand(app, global),
        far::cli::AddPlayCommand(app, global),
        far::cli::AddLoadCommand(app, global),
        far::cli::AddMakeSceneCommand(app),
        far::cli::AddRecordCommand(app, global, &record_command),
        far::cli::AddReplayCommand(app, global),
        far::cli::AddMovedSnapshotCommand(app),
    };
    const std::vector<std::string> args = far::cli::SplitRecordCommand(argc, argv, record_command);
    if (auto done = far::cli::ParseCommandLine(app, args)) return *done;
    for (const far::cli::Command& command : commands) {
      if (*command.app) return command.run();
    }
    return far::cli::kExitUsage;  // unreachable: require_subcommand(1)
  });
}
