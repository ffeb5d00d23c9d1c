#pragma once
// far-client's commands: one function per command file, each adding its subcommand to `app`.
// `global` outlives the run.
#include <string>
#include <vector>

#include "cli_common.h"

namespace far::cli {

Command AddPingCommand(CLI::App& app, const GlobalFlags& global);
Command AddStatusCommand(CLI::App& app, const GlobalFlags& global);
Command AddCollideCommand(CLI::App& app, const GlobalFlags& global);
Command AddPlayCommand(CLI::App& app, const GlobalFlags& global);
Command AddLoadCommand(CLI::App& app, const GlobalFlags& global);
Command AddMakeSceneCommand(CLI::App& app);
/// far-client record FILE COMMAND...: COMMAND's words are not far-client's to parse. Returns
/// argv without them (for CLI11) and puts them, without a leading "--", in `command_words`
/// (empty unless the command is record).
std::vector<std::string> SplitRecordCommand(int argc, char** argv,
                                            std::vector<std::string>& command_words);
Command AddRecordCommand(CLI::App& app, const GlobalFlags& global,
                         const std::vector<std::string>* command_words);
Command AddReplayCommand(CLI::App& app, const GlobalFlags& global);
/// "snapshot", hidden: it moved to its own program, far-snapshot; says so (kExitUsage).
Command AddMovedSnapshotCommand(CLI::App& app);

}  // namespace far::cli
