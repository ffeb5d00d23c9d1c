#include "far/protocol/lcm_log.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace far::protocol {
namespace {

uint64_t LoadBigEndian(const uint8_t* p, int bytes) {
  uint64_t value = 0;
  for (int i = 0; i < bytes; ++i) value = (value << 8) | p[i];
  return value;
}

void StoreBigEndian(uint8_t* p, uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) p[i] = static_cast<uint8_t>(value >> (8 * (bytes - 1 - i)));
}

std::string Where(uint64_t index, uint64_t offset) {
  return "event " + std::to_string(index) + " at byte " + std::to_string(offset);
}

}  // namespace

// ---- LcmLogReader ----------------------------------------------------------------------------

Result<std::unique_ptr<LcmLogReader>> LcmLogReader::Open(const std::string& path,
                                                         uint64_t max_event_bytes) {
  std::FILE* file = std::fopen(path.c_str(), "rbe");
  if (file == nullptr) {
    return MakeError(ErrorCode::kIoError, path + ": cannot open: " + std::strerror(errno));
  }
  struct stat info {};
  if (fstat(fileno(file), &info) != 0 || !S_ISREG(info.st_mode)) {
    std::fclose(file);
    return MakeError(ErrorCode::kIoError, path + ": not a regular file");
  }
  return std::unique_ptr<LcmLogReader>(
      new LcmLogReader(file, path, static_cast<uint64_t>(info.st_size), max_event_bytes));
}

LcmLogReader::LcmLogReader(std::FILE* file, std::string path, uint64_t file_size,
                           uint64_t max_event_bytes)
    : file_(file),
      path_(std::move(path)),
      file_size_(file_size),
      max_event_bytes_(max_event_bytes) {}

LcmLogReader::~LcmLogReader() { std::fclose(file_); }

Result<std::optional<LcmLogEvent>> LcmLogReader::Next() {
  if (failed_) return *failed_;
  if (next_offset_ == file_size_) return std::optional<LcmLogEvent>();
  auto event = ReadEventAt(next_offset_, next_index_);
  if (!event) {
    failed_ = event.error();
    return *failed_;
  }
  next_offset_ += kLcmLogEventHeaderBytes + event->channel.size() + event->data.size();
  ++next_index_;
  return std::optional<LcmLogEvent>(std::move(*event));
}

Result<LcmLogEvent> LcmLogReader::ReadAt(uint64_t offset) {
  // The index is unknown here: name the offset only.
  return ReadEventAt(offset, 0);
}

Result<LcmLogEvent> LcmLogReader::ReadEventAt(uint64_t offset, uint64_t index) {
  const std::string where = path_ + ": " + Where(index, offset);
  const auto truncated = [&](uint64_t need) {
    return MakeError(ErrorCode::kParseError, where + ": truncated: the event needs " +
                                                 std::to_string(need) + " bytes, the file has " +
                                                 std::to_string(file_size_ - offset) + " left");
  };
  if (offset > file_size_) return truncated(kLcmLogEventHeaderBytes);
  if (file_size_ - offset < kLcmLogEventHeaderBytes) return truncated(kLcmLogEventHeaderBytes);
  uint8_t header[kLcmLogEventHeaderBytes];
  if (fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0 ||
      std::fread(header, 1, sizeof(header), file_) != sizeof(header)) {
    return MakeError(ErrorCode::kIoError, where + ": read failed: " + std::strerror(errno));
  }
  const auto sync = static_cast<uint32_t>(LoadBigEndian(header, 4));
  if (sync != kLcmLogSyncWord) {
    char text[64];
    std::snprintf(text, sizeof(text), "sync word 0x%08X is not 0xEDA1DA01", sync);
    return MakeError(ErrorCode::kParseError,
                     where + ": " + text + (offset == 0 ? " (not an LCM log file)" : ""));
  }
  LcmLogEvent event;
  event.offset = offset;
  event.event_number = static_cast<int64_t>(LoadBigEndian(header + 4, 8));
  event.timestamp_us = static_cast<int64_t>(LoadBigEndian(header + 12, 8));
  const auto channel_length = static_cast<int32_t>(LoadBigEndian(header + 20, 4));
  const auto data_length = static_cast<int32_t>(LoadBigEndian(header + 24, 4));
  if (channel_length < 1 || static_cast<size_t>(channel_length) > kMaxLcmLogChannelBytes) {
    return MakeError(ErrorCode::kParseError,
                     where + ": channel length " + std::to_string(channel_length) +
                         " is outside [1, " + std::to_string(kMaxLcmLogChannelBytes) + "]");
  }
  if (data_length < 0) {
    return MakeError(ErrorCode::kParseError,
                     where + ": data length " + std::to_string(data_length) + " is negative");
  }
  if (static_cast<uint64_t>(data_length) > max_event_bytes_) {
    return MakeError(ErrorCode::kLimitExceeded,
                     where + ": data length " + std::to_string(data_length) + " is over the " +
                         std::to_string(max_event_bytes_) + "-byte limit");
  }
  // Both lengths against the bytes that are there, before anything is allocated.
  const uint64_t need = kLcmLogEventHeaderBytes + static_cast<uint64_t>(channel_length) +
                        static_cast<uint64_t>(data_length);
  if (file_size_ - offset < need) return truncated(need);
  event.channel.resize(static_cast<size_t>(channel_length));
  event.data.resize(static_cast<size_t>(data_length));
  if (std::fread(event.channel.data(), 1, event.channel.size(), file_) != event.channel.size() ||
      std::fread(event.data.data(), 1, event.data.size(), file_) != event.data.size()) {
    return MakeError(ErrorCode::kIoError, where + ": read failed (the file shrank?)");
  }
  return event;
}

// ---- LcmLogWriter ----------------------------------------------------------------------------

Result<std::unique_ptr<LcmLogWriter>> LcmLogWriter::FromDescriptor(int fd, std::string path) {
  std::FILE* file = fdopen(fd, "wb");
  if (file == nullptr) {
    const int error = errno;
    close(fd);
    return MakeError(ErrorCode::kIoError, path + ": cannot write: " + std::strerror(error));
  }
  return std::unique_ptr<LcmLogWriter>(new LcmLogWriter(file, std::move(path)));
}

LcmLogWriter::~LcmLogWriter() { std::fclose(file_); }

Error LcmLogWriter::IoError(const std::string& what) {
  failed_ = MakeError(ErrorCode::kIoError, path_ + ": " + what + ": " + std::strerror(errno));
  return *failed_;
}

Result<void> LcmLogWriter::Write(std::string_view channel, std::span<const uint8_t> data,
                                 int64_t timestamp_us) {
  if (failed_) return *failed_;
  if (channel.empty() || channel.size() > kMaxLcmLogChannelBytes) {
    return MakeError(ErrorCode::kInvalidArgument,
                     path_ + ": channel '" + std::string(channel) + "' is empty or too long");
  }
  if (data.size() > static_cast<size_t>(INT32_MAX)) {
    return MakeError(ErrorCode::kInvalidArgument, path_ + ": an event of " +
                                                      std::to_string(data.size()) +
                                                      " bytes is over the format's 2^31 - 1");
  }
  uint8_t header[kLcmLogEventHeaderBytes];
  StoreBigEndian(header, kLcmLogSyncWord, 4);
  StoreBigEndian(header + 4, static_cast<uint64_t>(next_event_), 8);
  StoreBigEndian(header + 12, static_cast<uint64_t>(timestamp_us), 8);
  StoreBigEndian(header + 20, channel.size(), 4);
  StoreBigEndian(header + 24, data.size(), 4);
  if (std::fwrite(header, 1, sizeof(header), file_) != sizeof(header) ||
      std::fwrite(channel.data(), 1, channel.size(), file_) != channel.size() ||
      std::fwrite(data.data(), 1, data.size(), file_) != data.size()) {
    return IoError("write failed");
  }
  ++next_event_;
  return {};
}

Result<void> LcmLogWriter::Flush() {
  if (failed_) return *failed_;
  if (std::fflush(file_) != 0) return IoError("write failed");
  return {};
}

}  // namespace far::protocol
