#pragma once

// LCM log files: the format lcm-logger writes and lcm-logplayer, lcm-spy and LCM's EventLog
// read (https://lcm-proj.github.io/lcm/content/log-file-format.html). A file is a sequence of
// events, each
//   uint32 sync word 0xEDA1DA01, int64 event number, int64 timestamp (microseconds),
//   int32 channel length, int32 data length, the channel (no NUL), the data
// with every integer big-endian. far records sessions in this format (recording.h) and its
// tests read lcm-logger's logs of live sessions with LcmLogReader.
//
// Why not LCM's own eventlog.c: its reader asserts (aborts) on a channel length of 1000 or
// more, allocates whatever data length the file claims, and skips garbage silently looking for
// the next sync word; a log file is untrusted input here. LcmLogReader checks every length
// against its limits and against the bytes the file has before it allocates, and stops at the
// first malformed event with an error that names its number and byte offset.

#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "far/base/result.h"

namespace far::protocol {

/// The sync word that starts every event.
inline constexpr uint32_t kLcmLogSyncWord = 0xEDA1DA01u;
/// Bytes of an event's fixed header (sync word, event number, timestamp, two lengths).
inline constexpr uint64_t kLcmLogEventHeaderBytes = 28;
/// The longest channel name far reads or writes (LCM's own limit is 63; eventlog.c's 999).
inline constexpr size_t kMaxLcmLogChannelBytes = 255;

/// One event of a log.
struct LcmLogEvent {
  int64_t event_number = 0;
  int64_t timestamp_us = 0;
  std::string channel;
  std::vector<uint8_t> data;
  uint64_t offset = 0;  ///< byte offset of its sync word in the file
};

/// Reads a log file as untrusted input. Thread safety: one thread at a time.
class LcmLogReader {
 public:
  /// Opens `path`. `max_event_bytes` bounds every event's data (the caller knows what its
  /// channels carry). Errors: kIoError (cannot open or stat it, not a regular file).
  static Result<std::unique_ptr<LcmLogReader>> Open(const std::string& path,
                                                    uint64_t max_event_bytes);
  ~LcmLogReader();
  LcmLogReader(const LcmLogReader&) = delete;
  LcmLogReader& operator=(const LcmLogReader&) = delete;

  /// The next event, or nullopt at the end of the file (exactly after an event's last byte).
  /// Errors (the message names the event's index and byte offset): kParseError for a wrong
  /// sync word, a channel length outside [1, kMaxLcmLogChannelBytes], a negative data length,
  /// a truncated event; kLimitExceeded for data over max_event_bytes; kIoError for a read error.
  /// After an error every later call returns it again.
  Result<std::optional<LcmLogEvent>> Next();

  /// The event at `offset` (an offset Next returned); the position for Next is unchanged.
  /// Errors: as Next, and kParseError when no event ends within the file there.
  Result<LcmLogEvent> ReadAt(uint64_t offset);

  /// The file's size when it was opened, bytes.
  uint64_t file_size() const { return file_size_; }
  const std::string& path() const { return path_; }

 private:
  LcmLogReader(std::FILE* file, std::string path, uint64_t file_size, uint64_t max_event_bytes);
  Result<LcmLogEvent> ReadEventAt(uint64_t offset, uint64_t index);

  std::FILE* file_;
  std::string path_;
  uint64_t file_size_;
  uint64_t max_event_bytes_;
  uint64_t next_offset_ = 0;
  uint64_t next_index_ = 0;
  std::optional<Error> failed_;
};

/// Writes a log file. Thread safety: one thread at a time.
class LcmLogWriter {
 public:
  /// Takes ownership of `fd`, a file open for writing (positioned at its start); `path` is for
  /// messages. Errors: kIoError.
  static Result<std::unique_ptr<LcmLogWriter>> FromDescriptor(int fd, std::string path);
  /// Flushes and closes.
  ~LcmLogWriter();
  LcmLogWriter(const LcmLogWriter&) = delete;
  LcmLogWriter& operator=(const LcmLogWriter&) = delete;

  /// Appends an event numbered 0, 1, 2, ... Errors: kInvalidArgument (channel empty or longer
  /// than kMaxLcmLogChannelBytes, data over 2^31 - 1 bytes), kIoError (a write failed; the
  /// writer fails every later call too, so that a recording is never silently cut).
  Result<void> Write(std::string_view channel, std::span<const uint8_t> data, int64_t timestamp_us);
  /// Pushes buffered events to the file. Errors: kIoError.
  Result<void> Flush();

  int64_t events_written() const { return next_event_; }
  const std::string& path() const { return path_; }

 private:
  LcmLogWriter(std::FILE* file, std::string path) : file_(file), path_(std::move(path)) {}
  Error IoError(const std::string& what);

  std::FILE* file_;
  std::string path_;
  int64_t next_event_ = 0;
  std::optional<Error> failed_;
};

}  // namespace far::protocol
