#include "far/protocol/ring.h"

#include <algorithm>
#include <cstring>
#include <thread>

#include "shm_access.h"

namespace far::protocol {
namespace {

// Copies `size` bytes of the ring's byte stream starting at `index` out of the ring.
void CopyOut(const RingRegion& region, uint64_t index, uint8_t* out, uint64_t size) {
  const uint64_t offset = index & (region.capacity - 1);
  const uint64_t first = std::min(size, region.capacity - offset);
  std::memcpy(out, region.data + offset, first);
  std::memcpy(out + first, region.data, size - first);
}

// Copies `size` bytes into the ring's byte stream at `index`.
void CopyIn(const RingRegion& region, uint64_t index, const uint8_t* in, uint64_t size) {
  const uint64_t offset = index & (region.capacity - 1);
  const uint64_t first = std::min(size, region.capacity - offset);
  std::memcpy(region.data + offset, in, first);
  std::memcpy(region.data, in + first, size - first);
}

std::string Where(const RingRegion& region, uint64_t sequence, uint64_t index) {
  return region.name + ": record " + std::to_string(sequence) + " at index " +
         std::to_string(index) + ": ";
}

Error Truncated(const RingRegion& region) {
  return MakeError(
      ErrorCode::kParseError,
      region.name + ": the shared-memory segment was truncated by its peer (SIGBUS caught)");
}

}  // namespace

// ---- RingWriter ----------------------------------------------------------------------------

RingWriter::RingWriter(RingRegion region) : region_(std::move(region)) {}

Result<RecordPosition> RingWriter::Write(RecordType type,
                                         std::initializer_list<std::span<const uint8_t>> body) {
  // Size the record in 64 bits; it must fit the ring and the header's uint32 size.
  uint64_t body_bytes = 0;
  for (const auto& part : body) body_bytes += part.size();
  const uint64_t size = AlignRecordSize(sizeof(RecordHeader) + body_bytes);
  if (size > region_.capacity || size > UINT32_MAX - kRecordAlignment) {
    return MakeError(ErrorCode::kLimitExceeded,
                     region_.name + ": a record of " + std::to_string(size) +
                         " bytes is larger than the ring's capacity of " +
                         std::to_string(region_.capacity) + " bytes");
  }

  internal::ScopedShmAccess access(region_.mapping);
  if (access.faulted()) return Truncated(region_);
  // The consumer's index, loaded once and checked before use.
  const uint64_t read = region_.read_index->load(std::memory_order_acquire);
  if (read > write_index_ || write_index_ - read > region_.capacity) {
    return MakeError(ErrorCode::kParseError,
                     region_.name + ": the consumer's read index " + std::to_string(read) +
                         " is inconsistent with the write index " + std::to_string(write_index_));
  }
  const uint64_t free = region_.capacity - (write_index_ - read);
  if (size > free) {
    return MakeError(ErrorCode::kBusy, region_.name + ": " + std::to_string(size) +
                                           " bytes needed, " + std::to_string(free) + " free");
  }

  // Header, body parts, zero padding; then publish.
  RecordPosition position{next_sequence_, write_index_, size};
  const RecordHeader header{static_cast<uint32_t>(type), static_cast<uint32_t>(size),
                            next_sequence_};
  uint64_t at = write_index_;
  CopyIn(region_, at, reinterpret_cast<const uint8_t*>(&header), sizeof(header));
  at += sizeof(header);
  for (const auto& part : body) {
    CopyIn(region_, at, part.data(), part.size());
    at += part.size();
  }
  static constexpr uint8_t kZeros[kRecordAlignment] = {};
  CopyIn(region_, at, kZeros, write_index_ + size - at);
  if (access.faulted()) return Truncated(region_);
  write_index_ += size;
  ++next_sequence_;
  region_.write_index->store(write_index_, std::memory_order_release);
  return position;
}

Result<RecordPosition> RingWriter::WriteWait(RecordType type,
                                             std::initializer_list<std::span<const uint8_t>> body,
                                             std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  auto pause = std::chrono::microseconds(50);
  while (true) {
    auto written = Write(type, body);
    if (written || written.error().code != ErrorCode::kBusy) return written;
    if (std::chrono::steady_clock::now() >= deadline) {
      return MakeError(ErrorCode::kTimeout, written.error().message + " after waiting " +
                                                std::to_string(timeout.count()) + " ms");
    }
    std::this_thread::sleep_for(pause);
    pause = std::min<std::chrono::microseconds>(pause * 2, std::chrono::milliseconds(1));
  }
}

// ---- RingReader ----------------------------------------------------------------------------

RingReader::RingReader(RingRegion region, uint64_t max_record_bytes)
    : region_(std::move(region)), max_record_bytes_(std::min(max_record_bytes, region_.capacity)) {}

Error RingReader::Corrupt(Error error) {
  error.message += " (ring is corrupt; open a new session)";
  corrupt_ = error;
  return error;
}

Result<uint64_t> RingReader::LoadWriteIndex() {
  // Loaded once; everything below uses the local.
  const uint64_t write = region_.write_index->load(std::memory_order_acquire);
  if (write < read_index_) {
    return Corrupt(MakeError(ErrorCode::kParseError, region_.name + ": write_index " +
                                                         std::to_string(write) +
                                                         " went backwards (read index " +
                                                         std::to_string(read_index_) + ")"));
  }
  if (write - read_index_ > region_.capacity) {
    return Corrupt(MakeError(ErrorCode::kParseError,
                             region_.name + ": write_index " + std::to_string(write) +
                                 " is more than the capacity " + std::to_string(region_.capacity) +
                                 " ahead of read index " + std::to_string(read_index_)));
  }
  return write;
}

Result<RawRecord> RingReader::CopyRecord(uint64_t index, uint64_t write,
                                         uint64_t expected_sequence) {
  const uint64_t committed = write - index;
  const std::string where = Where(region_, expected_sequence, index);
  if (committed < sizeof(RecordHeader)) {
    return Corrupt(MakeError(ErrorCode::kParseError,
                             where + "only " + std::to_string(committed) +
                                 " bytes committed, a record header needs 16 (truncated record)"));
  }
  // The header: copied once, checked, and only the copy is used from here on.
  RawRecord record;
  record.index = index;
  CopyOut(region_, index, reinterpret_cast<uint8_t*>(&record.header), sizeof(RecordHeader));
  const RecordHeader& header = record.header;
  if (header.size < sizeof(RecordHeader)) {
    return Corrupt(
        MakeError(ErrorCode::kParseError, where + "size " + std::to_string(header.size) +
                                              " is smaller than the 16-byte record header"));
  }
  if (header.size % kRecordAlignment != 0) {
    return Corrupt(MakeError(ErrorCode::kParseError, where + "size " + std::to_string(header.size) +
                                                         " is not a multiple of 8"));
  }
  if (header.size > committed) {
    return Corrupt(
        MakeError(ErrorCode::kParseError, where + "size " + std::to_string(header.size) +
                                              " runs past the end of the committed data (" +
                                              std::to_string(committed) + " bytes)"));
  }
  if (header.size > max_record_bytes_) {
    return Corrupt(MakeError(ErrorCode::kLimitExceeded,
                             where + "size " + std::to_string(header.size) + " is over the " +
                                 std::to_string(max_record_bytes_) + "-byte record limit"));
  }
  if (header.sequence != expected_sequence) {
    return Corrupt(MakeError(ErrorCode::kParseError, where + "sequence " +
                                                         std::to_string(header.sequence) +
                                                         " is out of order (expected " +
                                                         std::to_string(expected_sequence) + ")"));
  }
  if (copy_hook_) copy_hook_(header);
  // The whole record into private memory; its header bytes are replaced by the checked copy.
  // (assign from the ring's bytes: no zero fill of a buffer about to be overwritten)
  const uint64_t offset = index & (region_.capacity - 1);
  const uint64_t first = std::min<uint64_t>(header.size, region_.capacity - offset);
  record.bytes.reserve(header.size);
  record.bytes.assign(region_.data + offset, region_.data + offset + first);
  record.bytes.insert(record.bytes.end(), region_.data, region_.data + (header.size - first));
  std::memcpy(record.bytes.data(), &header, sizeof(RecordHeader));
  return record;
}

Result<std::vector<RawRecord>> RingReader::ReadUpTo(uint64_t up_to_sequence) {
  if (corrupt_) return *corrupt_;
  if (up_to_sequence < last_sequence_) {
    return MakeError(ErrorCode::kInvalidArgument, region_.name + ": sequence " +
                                                      std::to_string(up_to_sequence) +
                                                      " is before the last record already read (" +
                                                      std::to_string(last_sequence_) + ")");
  }
  std::vector<RawRecord> records;
  if (up_to_sequence == last_sequence_) return records;

  internal::ScopedShmAccess access(region_.mapping);
  if (access.faulted()) return Corrupt(Truncated(region_));
  auto write = LoadWriteIndex();
  if (!write) {
    if (access.faulted()) return Corrupt(Truncated(region_));
    return write.error();
  }
  uint64_t index = read_index_;
  uint64_t sequence = last_sequence_;
  while (sequence < up_to_sequence) {
    if (index == *write) {
      // Not (yet) written: the client asked for more than it committed. Nothing consumed.
      return MakeError(ErrorCode::kInvalidArgument,
                       region_.name + ": sequence " + std::to_string(up_to_sequence) +
                           " is not committed: the ring holds records up to " +
                           std::to_string(sequence));
    }
    auto record = CopyRecord(index, *write, sequence + 1);
    if (!record) {
      // Zeros read from a truncated segment look like a bad record; say what happened.
      if (access.faulted()) return Corrupt(Truncated(region_));
      return record.error();
    }
    index += record->header.size;
    ++sequence;
    records.push_back(std::move(*record));
  }
  if (access.faulted()) return Corrupt(Truncated(region_));
  // Consumed: the producer may reuse the space.
  read_index_ = index;
  last_sequence_ = sequence;
  region_.read_index->store(read_index_, std::memory_order_release);
  if (access.faulted()) return Corrupt(Truncated(region_));
  return records;
}

Result<std::optional<RawRecord>> RingReader::ReadNext() {
  if (corrupt_) return *corrupt_;
  internal::ScopedShmAccess access(region_.mapping);
  if (access.faulted()) return Corrupt(Truncated(region_));
  auto write = LoadWriteIndex();
  if (!write) {
    if (access.faulted()) return Corrupt(Truncated(region_));
    return write.error();
  }
  if (*write == read_index_) return std::optional<RawRecord>();
  auto record = CopyRecord(read_index_, *write, last_sequence_ + 1);
  if (!record) {
    if (access.faulted()) return Corrupt(Truncated(region_));
    return record.error();
  }
  if (access.faulted()) return Corrupt(Truncated(region_));
  read_index_ += record->header.size;
  last_sequence_ = record->header.sequence;
  region_.read_index->store(read_index_, std::memory_order_release);
  if (access.faulted()) return Corrupt(Truncated(region_));
  return std::optional<RawRecord>(std::move(*record));
}

}  // namespace far::protocol
