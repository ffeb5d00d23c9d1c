#pragma once
// What the tools share: the global flags, parsing the command line, failing with one line, a
// clock. Every error a tool meets ends in one line on stderr and an exit status, never an abort.
#include <chrono>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>

#include "far/base/result.h"
#include "far/client/client.h"

namespace far::cli {

using Clock = std::chrono::steady_clock;

/// Exit statuses every tool shares: 1 the command failed, 2 the command line is wrong.
inline constexpr int kExitFailure = 1;
inline constexpr int kExitUsage = 2;

/// Names the program in every message ("far-client", "far-snapshot"); set once, in main.
void SetProgramName(std::string_view name);
const std::string& ProgramName();

/// Flags given before or after the command: which daemon, and how long to look for it.
struct GlobalFlags {
  client::ClientOptions options;
  std::string connect_timeout = "1s";

  /// The client options the user asked for (valid once parsed; commands that run steps set
  /// their own step timeout).
  Result<client::ClientOptions> Options() const;
};

/// Parses a duration: a number with its unit, "500ms", "60s", "2min" (or "2m"). A bare number
/// is an error: "5" could mean seconds or milliseconds. Errors: kInvalidArgument naming `flag`.
Result<std::chrono::milliseconds> ParseDuration(const std::string& flag, const std::string& text);

/// A registered subcommand and what running it does (its exit status).
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

/// Parses `args` (argv[0] first) into `app`. Returns the exit status when the program is done:
/// 0 after --help; kExitUsage after one line "<program>: <what is wrong>" on stderr (an
/// unknown command is named and the known ones listed). nullopt: parsed, go on.
std::optional<int> ParseCommandLine(CLI::App& app, std::vector<std::string> args);

/// Runs `body` and turns an exception that escapes it (a bug, or memory running out) into one
/// line on stderr and kExitFailure instead of an abort.
int RunGuarded(const std::function<int()>& body);

/// Prints "<program>: <error>" to stderr; returns kExitFailure.
int Fail(const Error& error);

inline double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

/// Checks that `path` can be written as a file before the work that makes its content is
/// done: creates it when missing (and removes it again), never truncates one that exists.
/// Errors: kIoError naming `flag` and the path ("--png: /etc/hostname/x.png: cannot write:
/// Not a directory").
Result<void> CheckWritableFile(const std::string& flag, const std::string& path);

}  // namespace far::cli
