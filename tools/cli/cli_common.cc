#include "cli_common.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <exception>
#include <filesystem>

namespace far::cli {
namespace {

std::string& MutableProgramName() {
  static std::string name = "far";
  return name;
}

// The commands a user may type: every subcommand but the hidden ones (no group).
std::string CommandNames(const CLI::App& app) {
  std::string names;
  for (const CLI::App* command :
       app.get_subcommands([](const CLI::App* c) { return !c->get_group().empty(); })) {
    names += (names.empty() ? "" : ", ") + command->get_name();
  }
  return names;
}

// One line for a command line CLI11 refused. CLI11's own words, except where no command was
// recognized: then the word that was taken for one, and the commands there are.
std::string UsageMessage(const CLI::App& app, const CLI::ParseError& error) {
  const bool has_commands = app.get_require_subcommand_min() > 0;
  if (!has_commands || !app.get_subcommands().empty()) return error.what();
  const std::vector<std::string> unparsed = app.remaining();
  for (const std::string& word : unparsed) {
    if (word.starts_with("-")) continue;
    return "'" + word + "' is not a command; the commands are: " + CommandNames(app);
  }
  if (!unparsed.empty()) return error.what();
  return "a command is required: " + CommandNames(app) + " (" + app.get_name() + " --help)";
}

}  // namespace

void SetProgramName(std::string_view name) { MutableProgramName() = std::string(name); }
const std::string& ProgramName() { return MutableProgramName(); }

int Fail(const Error& error) {
  std::fprintf(stderr, "%s: %s\n", ProgramName().c_str(), ToString(error).c_str());
  return kExitFailure;
}

Result<std::chrono::milliseconds> ParseDuration(const std::string& flag, const std::string& text) {
  size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  const std::string unit = text.substr(used);
  if (used > 0 && unit.empty()) {
    return MakeError(ErrorCode::kInvalidArgument, flag + ": '" + text + "' has no unit: write " +
                                                      text + "ms, " + text + "s or " + text +
                                                      "min");
  }
  double ms_per_unit = 0;
  if (unit == "s") {
    ms_per_unit = 1000;
  } else if (unit == "ms") {
    ms_per_unit = 1;
  } else if (unit == "m" || unit == "min") {
    ms_per_unit = 60'000;
  }
  const double ms = value * ms_per_unit;
  if (used == 0 || ms_per_unit == 0 || !std::isfinite(ms) || ms <= 0 || ms > 86'400'000) {
    return MakeError(
        ErrorCode::kInvalidArgument,
        flag + ": '" + text + "' is not a duration between 1 ms and 24 h, like 500ms, 60s or 2min");
  }
  return std::chrono::milliseconds(static_cast<int64_t>(std::ceil(ms)));
}

Result<client::ClientOptions> GlobalFlags::Options() const {
  client::ClientOptions o = options;
  auto connect = ParseDuration("--connect-timeout", connect_timeout);
  if (!connect) return connect.error();
  o.connect_timeout = *connect;
  return o;
}

std::optional<int> ParseCommandLine(CLI::App& app, std::vector<std::string> args) {
  std::vector<char*> pointers;
  for (std::string& arg : args) pointers.push_back(arg.data());
  try {
    app.parse(static_cast<int>(pointers.size()), pointers.data());
    return std::nullopt;
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help: the help of the command it follows, on stdout
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "%s: %s\n", ProgramName().c_str(), UsageMessage(app, e).c_str());
    return kExitUsage;
  }
}

int RunGuarded(const std::function<int()>& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: internal error: %s\n", ProgramName().c_str(), e.what());
  } catch (...) {
    std::fprintf(stderr, "%s: internal error: an unknown exception\n", ProgramName().c_str());
  }
  return kExitFailure;
}

Result<void> CheckWritableFile(const std::string& flag, const std::string& path) {
  const std::string where = (flag.empty() ? "" : flag + ": ") + path;
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    return MakeError(ErrorCode::kIoError, where + ": is a directory, not a file");
  }
  const bool existed = std::filesystem::exists(path, ec);
  // Append mode creates a missing file and leaves an existing one as it is.
  FILE* file = std::fopen(path.c_str(), "ab");
  if (file == nullptr) {
    return MakeError(ErrorCode::kIoError, where + ": cannot write: " + std::strerror(errno));
  }
  std::fclose(file);
  if (!existed) std::filesystem::remove(path, ec);
  return {};
}

}  // namespace far::cli
