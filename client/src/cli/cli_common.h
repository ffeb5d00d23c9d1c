#pragma once
// What every far-client command shares: the global flags, failing with a message, a clock.
#include <chrono>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "far/base/result.h"
#include "far/client/client.h"

namespace far::cli {

using Clock = std::chrono::steady_clock;

/// Flags given before or after the command: which daemon, and how long to look for it.
struct GlobalFlags {
  client::ClientOptions options;
  std::string connect_timeout = "1s";

  /// The client options the user asked for (valid once parsed; commands that run steps set
  /// their own step timeout).
  Result<client::ClientOptions> Options() const;
};

/// Parses a duration: a number with a unit, "500ms", "60s", "2m" (a bare number is seconds).
/// Errors: kInvalidArgument naming `flag`.
Result<std::chrono::milliseconds> ParseDuration(const std::string& flag, const std::string& text);

/// A registered subcommand and what running it does (its exit status).
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

/// Prints "far-client: <error>" to stderr; returns the exit status 1.
inline int Fail(const Error& error) {
  std::fprintf(stderr, "far-client: %s\n", ToString(error).c_str());
  return 1;
}

inline double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// One function per command file; each adds its subcommand to `app`. `global` outlives the run.
Command AddPingCommand(CLI::App& app, const GlobalFlags& global);
Command AddStatusCommand(CLI::App& app, const GlobalFlags& global);
Command AddCollideCommand(CLI::App& app, const GlobalFlags& global);
Command AddPlayCommand(CLI::App& app, const GlobalFlags& global);
Command AddLoadCommand(CLI::App& app, const GlobalFlags& global);
Command AddMakeSceneCommand(CLI::App& app);
Command AddSnapshotCommand(CLI::App& app);
/// far-client record FILE COMMAND...: COMMAND's words are not far-client's to parse. Returns
/// argv without them (for CLI11) and puts them, without a leading "--", in `command_words`
/// (empty unless the command is record).
std::vector<std::string> SplitRecordCommand(int argc, char** argv,
                                            std::vector<std::string>& command_words);
Command AddRecordCommand(CLI::App& app, const GlobalFlags& global,
                         const std::vector<std::string>* command_words);
Command AddReplayCommand(CLI::App& app, const GlobalFlags& global);

}  // namespace far::cli
