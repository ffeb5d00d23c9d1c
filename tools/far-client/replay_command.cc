// far-client replay: runs a far recording (far-client record, FAR_RECORD) against a daemon in
// a new session and checks that every reply matches the recorded one (docs/record-replay.md).
#include <cstdio>

#include "cli_common.h"
#include "commands.h"
#include "replay_compare.h"
#include "step_flags.h"

#include "far/client/internal/client_access.h"
#include "far/protocol/recording.h"

namespace far::cli {
namespace {

// Exit statuses: 0 every reply matches, 1 a mismatch, 2 no replay (bad recording, no daemon).
constexpr int kExitMismatch = 1;
constexpr int kExitError = 2;

// The longest a recorded ring record waits for room in the new session's ring.
constexpr std::chrono::seconds kRingWait{5};

struct ReplayFlags {
  std::string file;
  std::string timeout = "60s";
  bool strict = false;
  bool quiet = false;
};

int Error2(const Error& error) {
  std::fprintf(stderr, "far-client replay: %s\n", ToString(error).c_str());
  return kExitError;
}

// Writes the records step `step` commits into the session's ring, as recorded.
Result<void> WriteRecords(protocol::LcmLogReader& log, const protocol::RecordedStep& step,
                          client::Client& session) {
  return client::internal::ClientAccess::WriteUpdates(
      session, [&](protocol::UpdateWriter& writer) -> Result<void> {
        for (uint64_t offset : step.ring_record_offsets) {
          auto recorded = protocol::ReadRecordedUpdate(log, offset);
          if (!recorded) return recorded.error();
          auto written = protocol::WriteRecordedUpdate(writer, recorded->update, kRingWait);
          if (!written) {
            return MakeError(written.error().code, "ring record " +
                                                       std::to_string(recorded->sequence) + ": " +
                                                       written.error().message);
          }
        }
        if (writer.last_sequence() != step.command.ring_commit_sequence) {
          return MakeError(ErrorCode::kInternal,
                           "the ring holds records up to " +
                               std::to_string(writer.last_sequence()) +
                               ", the recorded step committed " +
                               std::to_string(step.command.ring_commit_sequence));
        }
        return {};
      });
}

void PrintHeader(const ReplayFlags& flags, const protocol::RecordingIndex& index,
                 const std::string& renderer) {
  const auto& h = index.header;
  std::printf(
      "replaying %s: %zu steps, %llu ring records; recorded by '%s' (far %s) on daemon "
      "'%s', renderer '%s'; replaying on renderer '%s'\n",
      flags.file.c_str(), index.steps.size(), static_cast<unsigned long long>(index.ring_records),
      h.client_name.c_str(), h.far_version.c_str(), h.daemon_name.c_str(), h.gl_renderer.c_str(),
      renderer.c_str());
  if (index.uncommitted_records > 0) {
    std::printf("  %llu ring records after the last step are not replayed\n",
                static_cast<unsigned long long>(index.uncommitted_records));
  }
}

void PrintStep(size_t n, const protocol::RecordedStep& step, const StepComparison& comparison,
               bool quiet) {
  const char* verdict = !comparison.compared   ? "not compared"
                        : comparison.matches() ? "match"
                                               : "MISMATCH";
  if (!quiet || !comparison.matches()) {
    std::printf("step %3zu (recorded step %lld)  %s  %s\n", n,
                static_cast<long long>(step.command.step_id), verdict, comparison.summary.c_str());
  }
  for (const std::string& m : comparison.mismatches) std::printf("      mismatch: %s\n", m.c_str());
  if (!quiet) {
    for (const std::string& note : comparison.notes) std::printf("      note: %s\n", note.c_str());
  }
}

struct Tally {
  size_t matched = 0, not_compared = 0, no_reply = 0, noted = 0;
  std::optional<std::string> first_mismatch;
};

int PrintVerdict(const protocol::RecordingIndex& index, const Tally& tally) {
  if (tally.first_mismatch) {
    std::printf("replay: MISMATCH: %s\n", tally.first_mismatch->c_str());
    return kExitMismatch;
  }
  std::printf(
      "replay: %zu steps, every compared reply matches (%zu compared, %zu not compared, "
      "%zu without a recorded reply, %zu with allowed differences)\n",
      index.steps.size(), tally.matched, tally.not_compared, tally.no_reply, tally.noted);
  return 0;
}

// The options of the replay's session: the global daemon flags, --timeout, never recorded
// itself.
Result<client::ClientOptions> ReplayOptions(const GlobalFlags& global, const ReplayFlags& flags) {
  auto options = global.Options();
  if (!options) return options.error();
  auto timeout = ParseDuration("--timeout", flags.timeout);
  if (!timeout) return timeout.error();
  options->timeout = *timeout;
  options->client_name = "far-client replay";
  options->record_path = std::string();
  return options;
}

int RunReplay(const GlobalFlags& global, const ReplayFlags& flags) {
  // The flags first: a bad one is said before any file is read.
  auto options = ReplayOptions(global, flags);
  if (!options) return Error2(options.error());
  auto log = protocol::OpenRecording(flags.file);
  if (!log) return Error2(log.error());
  auto index = protocol::IndexRecording(**log);
  if (!index) return Error2(index.error());
  auto session = client::Client::Connect(*options);
  if (!session) return Error2(session.error());
  std::string renderer;  // "" when the daemon does not say: PCS differences are then allowed
  if (auto options = global.Options(); options) {
    if (auto status = client::Client::Status(*options); status) renderer = status->gl_renderer;
  }
  PrintHeader(flags, *index, renderer);
  CompareOptions compare;
  compare.same_renderer = !renderer.empty() && renderer == index->header.gl_renderer;
  compare.strict = flags.strict;
  Tally tally;
  for (size_t n = 0; n < index->steps.size(); ++n) {
    const protocol::RecordedStep& step = index->steps[n];
    if (auto ok = WriteRecords(**log, step, **session); !ok) {
      return Error2(
          MakeError(ok.error().code, "step " + std::to_string(n) + ": " + ok.error().message));
    }
    const Result<StepResult> replayed = (*session)->Step(step.command.request);
    if (!step.reply_offset) {
      ++tally.no_reply;
      std::printf("step %3zu (recorded step %lld)  no recorded reply, not compared\n", n,
                  static_cast<long long>(step.command.step_id));
      continue;
    }
    auto recorded = protocol::ReadRecordedReply(**log, *step.reply_offset);
    if (!recorded) return Error2(recorded.error());
    const StepComparison comparison = CompareStep(recorded->result, replayed, compare);
    PrintStep(n, step, comparison, flags.quiet);
    if (!comparison.compared) {
      ++tally.not_compared;
    } else if (comparison.matches()) {
      ++tally.matched;
      if (!comparison.notes.empty()) ++tally.noted;
    } else if (!tally.first_mismatch) {
      tally.first_mismatch = "step " + std::to_string(n) + " (recorded step " +
                             std::to_string(step.command.step_id) +
                             "): " + comparison.mismatches.front();
    }
  }
  return PrintVerdict(*index, tally);
}

}  // namespace

Command AddReplayCommand(CLI::App& app, const GlobalFlags& global) {
  auto flags = std::make_shared<ReplayFlags>();
  Command command;
  command.app = app.add_subcommand(
      "replay",
      "Run a far recording (far-client record, FAR_RECORD) against the daemon in a new session\n"
      "and check each reply against the recorded one: contacts and distance pairs exactly, the\n"
      "PCS exactly when the method and renderer are the same (--strict: always). One line per\n"
      "step, then a verdict. Exit 0: every reply matches; 1: a mismatch (the first is named);\n"
      "2: no replay (the recording is unreadable, no daemon)");
  command.app->add_option("file", flags->file, "a far recording (.farrec)")->required();
  command.app
      ->add_option("--timeout", flags->timeout,
                   "wait this long for each step's reply (500ms, 60s, 2min: a unit is required)")
      ->capture_default_str();
  command.app->add_flag("--strict", flags->strict,
                        "fail on any difference, the PCS and object pairs included, whatever "
                        "the renderer");
  command.app->add_flag("--quiet", flags->quiet, "print only mismatching steps and the verdict");
  command.run = [&global, flags] { return RunReplay(global, *flags); };
  return command;
}

}  // namespace far::cli
