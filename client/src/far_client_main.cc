// far-client: probe a running far-daemon, run scene files through it, load-test it, draw a
// step of a scene (snapshot, in process), record a session and replay it.
// Usage and examples: far-client --help, far-client <command> --help, README.md.
// Each command lives in its own file under cli/.
#include <cstdio>
#include <string>
#include <vector>

#include "cli/cli_common.h"

int main(int argc, char** argv) {
  // Every line reaches a pipe as it is printed (deploy/run-demo.sh prefixes each client's lines
  // as they come), not in one burst when the buffer fills or the command ends.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  CLI::App app{"far-client: probe a far-daemon, run scene files through it, load-test it"};
  app.require_subcommand(1);
  app.fallthrough();  // the global flags may also come after the command
  far::cli::GlobalFlags global;
  std::vector<std::string> record_command;  // far-client record FILE <these words>
  app.add_option("--daemon", global.options.daemon,
                 "the daemon's name (far-daemon --name): its socket is <dir>/<name>.sock")
      ->capture_default_str();
  app.add_option("--socket", global.options.socket_path,
                 "the daemon's socket path, when not the default for its name");
  app.add_option("--lcm-url", global.options.lcm_url,
                 "LCM URL of the session channels (default: the one the daemon names)");
  app.add_option("--connect-timeout", global.connect_timeout,
                 "how long to look for a daemon that is not (yet) there before saying so")
      ->capture_default_str();

  const std::vector<far::cli::Command> commands = {
      far::cli::AddPingCommand(app, global),
      far::cli::AddStatusCommand(app, global),
      far::cli::AddCollideCommand(app, global),
      far::cli::AddPlayCommand(app, global),
      far::cli::AddLoadCommand(app, global),
      far::cli::AddMakeSceneCommand(app),
      far::cli::AddSnapshotCommand(app),
      far::cli::AddRecordCommand(app, global, &record_command),
      far::cli::AddReplayCommand(app, global),
  };
  std::vector<std::string> args = far::cli::SplitRecordCommand(argc, argv, record_command);
  std::vector<char*> arg_pointers;
  for (std::string& arg : args) arg_pointers.push_back(arg.data());
  const int parsed_argc = static_cast<int>(arg_pointers.size());
  char** parsed_argv = arg_pointers.data();
  CLI11_PARSE(app, parsed_argc, parsed_argv);
  for (const far::cli::Command& command : commands) {
    if (*command.app) return command.run();
  }
  return 1;  // unreachable: require_subcommand(1)
}
