// far-client record: runs a command with FAR_RECORD set, so that the far session it opens is
// recorded into one file (docs/record-replay.md): a simulator linking far::client, or one of
// far-client's own commands (play, collide, load, ...).
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <set>

#include "cli_common.h"
#include "commands.h"

#include "far/protocol/recording.h"

extern char** environ;

namespace far::cli {
namespace {

struct RecordFlags {
  std::string file;
  std::vector<std::string> command;  // what follows FILE (and "--"): the command, its arguments
};

const std::set<std::string>& OwnCommands() {
  static const std::set<std::string> commands = {"ping", "status", "collide", "play", "load"};
  return commands;
}

// The command line to run: far-client's own commands run this far-client with the global
// flags it was given; anything else is a program found on PATH.
std::vector<std::string> ChildArgv(const RecordFlags& flags, const GlobalFlags& global) {
  std::vector<std::string> argv = flags.command;
  if (argv.empty() || OwnCommands().count(argv[0]) == 0) return argv;
  std::error_code ignored;
  argv.insert(argv.begin(), std::filesystem::read_symlink("/proc/self/exe", ignored).string());
  const client::ClientOptions& o = global.options;
  if (!o.daemon.empty()) argv.insert(argv.end(), {"--daemon", o.daemon});
  if (!o.socket_path.empty()) argv.insert(argv.end(), {"--socket", o.socket_path});
  if (!o.lcm_url.empty()) argv.insert(argv.end(), {"--lcm-url", o.lcm_url});
  argv.insert(argv.end(), {"--connect-timeout", global.connect_timeout});
  return argv;
}

// This process's environment with FAR_RECORD=<file>.
std::vector<std::string> ChildEnvironment(const std::string& file) {
  std::vector<std::string> env;
  for (char** e = environ; *e != nullptr; ++e) {
    if (std::strncmp(*e, "FAR_RECORD=", 11) != 0) env.emplace_back(*e);
  }
  env.push_back("FAR_RECORD=" + file);
  return env;
}

std::vector<char*> Pointers(std::vector<std::string>& strings) {
  std::vector<char*> pointers;
  for (std::string& s : strings) pointers.push_back(s.data());
  pointers.push_back(nullptr);
  return pointers;
}

// Runs argv with env and returns its exit code (128 + signal when a signal ended it).
Result<int> Run(std::vector<std::string> argv, std::vector<std::string> env) {
  std::vector<char*> args = Pointers(argv);
  std::vector<char*> envp = Pointers(env);
  pid_t pid = -1;
  const int spawned = posix_spawnp(&pid, args[0], nullptr, nullptr, args.data(), envp.data());
  if (spawned != 0) {
    return MakeError(ErrorCode::kUnavailable,
                     "cannot run '" + argv[0] + "': " + std::strerror(spawned));
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return MakeError(ErrorCode::kInternal, "waitpid failed");
  }
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return WEXITSTATUS(status);
}

// "recorded 31 steps (80 ring records, 1234567 bytes) to FILE", or why the file is not usable.
bool Describe(const std::string& file) {
  auto log = protocol::OpenRecording(file);
  if (!log) return false;
  auto index = protocol::IndexRecording(**log);
  if (!index) {
    std::fprintf(stderr, "far-client record: %s is not a usable recording: %s\n", file.c_str(),
                 ToString(index.error()).c_str());
    return false;
  }
  std::printf("far-client record: %zu steps (%llu ring records, %llu bytes) recorded to %s\n",
              index->steps.size(), static_cast<unsigned long long>(index->ring_records),
              static_cast<unsigned long long>((*log)->file_size()), file.c_str());
  return true;
}

int RunRecord(const GlobalFlags& global, const RecordFlags& flags) {
  std::vector<std::string> argv = ChildArgv(flags, global);
  if (argv.empty()) {
    return Fail(MakeError(ErrorCode::kInvalidArgument,
                          "record: no command to run (far-client record FILE play SCENE, or "
                          "far-client record FILE -- SIMULATOR ARGS...)"));
  }
  // FILE must be writable before the command runs: inside it, the library could only say so
  // after the command has connected (or failed to).
  if (auto ok = CheckWritableFile("record", flags.file); !ok) return Fail(ok.error());
  // FILE is replaced; the library never overwrites, so remove it first.
  std::error_code removed;
  std::filesystem::remove(flags.file, removed);
  if (removed) {
    return Fail(MakeError(ErrorCode::kIoError,
                          "record: cannot replace " + flags.file + ": " + removed.message()));
  }
  const auto started = std::filesystem::file_time_type::clock::now();
  auto code = Run(argv, ChildEnvironment(flags.file));
  if (!code) return Fail(code.error());
  std::error_code missing;
  if (!std::filesystem::exists(flags.file, missing)) {
    std::fprintf(stderr,
                 "far-client record: nothing was recorded to %s: '%s' opened no far session\n",
                 flags.file.c_str(), argv[0].c_str());
    return *code != 0 ? *code : 1;
  }
  bool usable = Describe(flags.file);
  // Further sessions of the command recorded to FILE's numbered siblings.
  for (int n = 2;; ++n) {
    const std::filesystem::path p(flags.file);
    const auto sibling =
        p.parent_path() / (p.stem().string() + "." + std::to_string(n) + p.extension().string());
    std::error_code error;
    const auto written = std::filesystem::last_write_time(sibling, error);
    if (error || written < started) break;
    usable = Describe(sibling.string()) && usable;
  }
  if (*code != 0) return *code;
  return usable ? 0 : 1;
}

}  // namespace

std::vector<std::string> SplitRecordCommand(int argc, char** argv,
                                            std::vector<std::string>& command_words) {
  std::vector<std::string> args(argv, argv + argc);
  static const std::set<std::string> kValueFlags = {"--daemon", "--socket", "--lcm-url",
                                                    "--connect-timeout"};
  for (size_t i = 1; i < args.size(); ++i) {
    if (kValueFlags.count(args[i]) != 0) {
      ++i;  // its value
      continue;
    }
    if (args[i].starts_with("-")) continue;
    // The first word that is no flag names the command; only record's words are taken.
    if (args[i] != "record" || i + 1 >= args.size() || args[i + 1].starts_with("-")) return args;
    command_words.assign(args.begin() + static_cast<std::ptrdiff_t>(i + 2), args.end());
    if (!command_words.empty() && command_words.front() == "--") {
      command_words.erase(command_words.begin());
    }
    args.resize(i + 2);
    return args;
  }
  return args;
}

Command AddRecordCommand(CLI::App& app, const GlobalFlags& global,
                         const std::vector<std::string>* command_words) {
  auto flags = std::make_shared<RecordFlags>();
  Command command;
  command.app = app.add_subcommand(
      "record",
      "Record the far session a command opens into FILE (a far recording: an LCM log of its\n"
      "ring records, step requests and replies; never the session key), for far-client replay:\n"
      "  far-client record run.farrec play scene.json --steps 20\n"
      "  far-client record run.farrec -- ./my_simulator --its-flags\n"
      "The command runs with FAR_RECORD=FILE, which every program linking far::client honours;\n"
      "more sessions of it record to FILE's stem .2, .3, ... Exit status: the command's.");
  command.app->add_option("file", flags->file, "the recording to write (replaced)")->required();
  command.run = [&global, flags, command_words] {
    RecordFlags all = *flags;
    all.command = *command_words;
    return RunRecord(global, all);
  };
  return command;
}

}  // namespace far::cli
