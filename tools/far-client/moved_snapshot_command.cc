// far-client snapshot: moved to far-snapshot (tools/far-snapshot), so that far-client links no
// GL, EGL or FCL. The old name says where the command went instead of "not a command".
#include "cli_common.h"
#include "commands.h"

namespace far::cli {

Command AddMovedSnapshotCommand(CLI::App& app) {
  Command command;
  command.app = app.add_subcommand("snapshot", "moved: far-snapshot SCENE --png FILE draws a step");
  // Hidden from --help, and takes whatever words came with it, to fail on the move alone.
  command.app->group("");
  command.app->fallthrough(false);
  command.app->allow_extras();
  command.app->set_help_flag();  // snapshot --help, too, says where the command went
  command.run = [] {
    std::fprintf(stderr,
                 "%s: snapshot is now its own program: far-snapshot SCENE --png FILE [options] "
                 "(far-snapshot --help)\n",
                 ProgramName().c_str());
    return kExitUsage;
  };
  return command;
}

}  // namespace far::cli
