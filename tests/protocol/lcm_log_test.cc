// LcmLogReader and LcmLogWriter: LCM's log file format, read as untrusted input, and checked
// against LCM's own reader and writer (eventlog.c).

#include "far/protocol/lcm_log.h"

#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/eventlog.h>

namespace far::protocol {
namespace {

class LcmLogTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("far-lcm-log-test-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  std::unique_ptr<LcmLogWriter> Writer(const std::string& path) {
    const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    EXPECT_GE(fd, 0);
    auto writer = LcmLogWriter::FromDescriptor(fd, path);
    EXPECT_TRUE(writer) << writer.error().message;
    return std::move(*writer);
  }

  static std::vector<uint8_t> ReadBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  static void WriteBytes(const std::string& path, const std::vector<uint8_t>& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
  }

  // Every event of `path`, or the first error.
  static Result<std::vector<LcmLogEvent>> ReadAll(const std::string& path, uint64_t cap = 1 << 20) {
    auto reader = LcmLogReader::Open(path, cap);
    if (!reader) return reader.error();
    std::vector<LcmLogEvent> events;
    for (;;) {
      auto event = (*reader)->Next();
      if (!event) return event.error();
      if (!event->has_value()) return events;
      events.push_back(std::move(**event));
    }
  }

  void WriteThreeEvents(const std::string& path) {
    auto writer = Writer(path);
    const std::vector<uint8_t> a = {1, 2, 3}, empty, b(1000, 7);
    ASSERT_TRUE(writer->Write("FARREC_HEADER", a, 100));
    ASSERT_TRUE(writer->Write("X", empty, 200));
    ASSERT_TRUE(writer->Write("FARREC_RING", b, -5));
    ASSERT_TRUE(writer->Flush());
  }

  std::filesystem::path dir_;
};

TEST_F(LcmLogTest, EventsRoundTripWithNumbersTimestampsAndOffsets) {
  const std::string path = Path("a.log");
  WriteThreeEvents(path);
  auto events = ReadAll(path);
  ASSERT_TRUE(events) << events.error().message;
  ASSERT_EQ(events->size(), 3u);
  EXPECT_EQ((*events)[0].channel, "FARREC_HEADER");
  EXPECT_EQ((*events)[0].data, (std::vector<uint8_t>{1, 2, 3}));
  EXPECT_EQ((*events)[0].timestamp_us, 100);
  EXPECT_EQ((*events)[0].offset, 0u);
  EXPECT_EQ((*events)[1].event_number, 1);
  EXPECT_TRUE((*events)[1].data.empty());
  EXPECT_EQ((*events)[1].offset, 28u + 13 + 3);
  EXPECT_EQ((*events)[2].timestamp_us, -5);
  EXPECT_EQ((*events)[2].data.size(), 1000u);

  auto reader = LcmLogReader::Open(path, 1 << 20);
  ASSERT_TRUE(reader);
  auto again = (*reader)->ReadAt((*events)[2].offset);
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_EQ(again->channel, "FARREC_RING");
  EXPECT_EQ(again->data, (*events)[2].data);
}

TEST_F(LcmLogTest, LcmsOwnReaderReadsWhatFarWrites) {
  const std::string path = Path("far.log");
  WriteThreeEvents(path);
  lcm_eventlog_t* log = lcm_eventlog_create(path.c_str(), "r");
  ASSERT_NE(log, nullptr);
  std::vector<std::string> channels;
  while (lcm_eventlog_event_t* event = lcm_eventlog_read_next_event(log)) {
    channels.emplace_back(event->channel, static_cast<size_t>(event->channellen));
    if (channels.size() == 3) {
      EXPECT_EQ(event->datalen, 1000);
      EXPECT_EQ(event->timestamp, -5);
      EXPECT_EQ(event->eventnum, 2);
    }
    lcm_eventlog_free_event(event);
  }
  lcm_eventlog_destroy(log);
  EXPECT_EQ(channels, (std::vector<std::string>{"FARREC_HEADER", "X", "FARREC_RING"}));
}

TEST_F(LcmLogTest, FarReadsWhatLcmsOwnWriterWrites) {
  const std::string path = Path("lcm.log");
  lcm_eventlog_t* log = lcm_eventlog_create(path.c_str(), "w");
  ASSERT_NE(log, nullptr);
  char channel[] = "FAR_S1_REQ";
  uint8_t data[5] = {9, 8, 7, 6, 5};
  lcm_eventlog_event_t event{};
  event.timestamp = 123456;
  event.channellen = 10;
  event.datalen = 5;
  event.channel = channel;
  event.data = data;
  ASSERT_EQ(lcm_eventlog_write_event(log, &event), 0);
  ASSERT_EQ(lcm_eventlog_write_event(log, &event), 0);
  lcm_eventlog_destroy(log);
  auto events = ReadAll(path);
  ASSERT_TRUE(events) << events.error().message;
  ASSERT_EQ(events->size(), 2u);
  EXPECT_EQ((*events)[1].channel, "FAR_S1_REQ");
  EXPECT_EQ((*events)[1].event_number, 1);
  EXPECT_EQ((*events)[1].timestamp_us, 123456);
  EXPECT_EQ((*events)[1].data, (std::vector<uint8_t>{9, 8, 7, 6, 5}));
}

TEST_F(LcmLogTest, AnEmptyFileHasNoEvents) {
  const std::string path = Path("empty.log");
  WriteBytes(path, {});
  auto events = ReadAll(path);
  ASSERT_TRUE(events) << events.error().message;
  EXPECT_TRUE(events->empty());
}

TEST_F(LcmLogTest, ANonLogFileIsRefusedAtItsFirstBytes) {
  const std::string path = Path("text.log");
  WriteBytes(path, std::vector<uint8_t>(100, 'a'));
  auto events = ReadAll(path);
  ASSERT_FALSE(events);
  EXPECT_EQ(events.error().code, ErrorCode::kParseError);
  EXPECT_NE(events.error().message.find("not an LCM log file"), std::string::npos)
      << events.error().message;
}

TEST_F(LcmLogTest, EveryTruncationIsAClearErrorNeverACrash) {
  const std::string path = Path("whole.log");
  WriteThreeEvents(path);
  const std::vector<uint8_t> whole = ReadBytes(path);
  const std::set<size_t> ends = {0, 44, 44 + 29, whole.size()};  // event boundaries
  for (size_t size = 0; size <= whole.size(); ++size) {
    const std::string cut = Path("cut.log");
    WriteBytes(cut, std::vector<uint8_t>(whole.begin(), whole.begin() + static_cast<long>(size)));
    auto events = ReadAll(cut);
    if (ends.count(size) != 0) {
      EXPECT_TRUE(events) << size << ": " << events.error().message;
    } else {
      ASSERT_FALSE(events) << "a file cut at byte " << size << " was accepted";
      EXPECT_EQ(events.error().code, ErrorCode::kParseError);
      EXPECT_NE(events.error().message.find("truncated"), std::string::npos)
          << events.error().message;
    }
  }
}

// Overwrites the big-endian int32 at `offset`.
void Put32(std::vector<uint8_t>& bytes, size_t offset, uint32_t value) {
  for (int i = 0; i < 4; ++i) bytes[offset + i] = static_cast<uint8_t>(value >> (24 - 8 * i));
}

TEST_F(LcmLogTest, BadLengthsAreRefusedBeforeAnythingIsAllocated) {
  const std::string path = Path("base.log");
  WriteThreeEvents(path);
  const std::vector<uint8_t> whole = ReadBytes(path);
  struct Case {
    size_t offset;
    uint32_t value;
    ErrorCode code;
    const char* says;
  };
  const Case cases[] = {
      {20, 0, ErrorCode::kParseError, "channel length 0"},
      {20, 256, ErrorCode::kParseError, "channel length 256"},
      {20, 0x80000000u, ErrorCode::kParseError, "channel length -2147483648"},
      {24, 0xFFFFFFFFu, ErrorCode::kParseError, "data length -1 is negative"},
      {24, 0x7FFFFFFFu, ErrorCode::kLimitExceeded, "over the 1048576-byte limit"},
      {24, 100000, ErrorCode::kParseError, "truncated"},
      {0, 0xEDA1DA02u, ErrorCode::kParseError, "sync word 0xEDA1DA02"},
  };
  for (const Case& c : cases) {
    std::vector<uint8_t> bytes = whole;
    Put32(bytes, c.offset, c.value);
    const std::string bad = Path("bad.log");
    WriteBytes(bad, bytes);
    auto events = ReadAll(bad);
    ASSERT_FALSE(events) << c.says;
    EXPECT_EQ(events.error().code, c.code) << events.error().message;
    EXPECT_NE(events.error().message.find(c.says), std::string::npos) << events.error().message;
    EXPECT_NE(events.error().message.find("event 0 at byte 0"), std::string::npos)
        << events.error().message;
  }
}

TEST_F(LcmLogTest, AnErrorIsSticky) {
  const std::string path = Path("sticky.log");
  WriteBytes(path, std::vector<uint8_t>(40, 0));
  auto reader = LcmLogReader::Open(path, 1024);
  ASSERT_TRUE(reader);
  auto first = (*reader)->Next();
  auto second = (*reader)->Next();
  ASSERT_FALSE(first);
  ASSERT_FALSE(second);
  EXPECT_EQ(first.error().message, second.error().message);
}

TEST_F(LcmLogTest, OpenNamesAMissingFileAndRefusesADirectory) {
  auto missing = LcmLogReader::Open(Path("nope.log"), 1024);
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::kIoError);
  EXPECT_NE(missing.error().message.find("nope.log"), std::string::npos);
  auto directory = LcmLogReader::Open(dir_.string(), 1024);
  ASSERT_FALSE(directory);
  EXPECT_EQ(directory.error().code, ErrorCode::kIoError);
}

TEST_F(LcmLogTest, TheWriterRefusesChannelsTheReaderWouldRefuse) {
  auto writer = Writer(Path("w.log"));
  const std::vector<uint8_t> data = {1};
  EXPECT_FALSE(writer->Write("", data, 0));
  EXPECT_FALSE(writer->Write(std::string(256, 'c'), data, 0));
  EXPECT_TRUE(writer->Write(std::string(255, 'c'), data, 0));
}

}  // namespace
}  // namespace far::protocol
