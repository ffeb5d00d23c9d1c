#pragma once

// A single-producer/single-consumer ring of variable-size records in shared memory (layout
// in ring_layout.h). The producer and the consumer live in different processes and do not
// trust each other's indices:
//   - each side keeps its own index privately and only *publishes* it to shared memory
//     (release); it never reads its own index back;
//   - the other side's index is loaded once per operation (acquire) into a local and checked
//     (monotonic, at most one capacity apart) before it is used;
//   - the consumer copies every record out of shared memory into private memory before it
//     looks at anything but the header, and copies the header once, checks it, and uses that
//     copy (the producer may change the bytes at any time: TOCTOU);
//   - records may wrap around the end of the ring; copies do it in two pieces. There are no
//     padding records.
// A framing error (bad indices, sizes, sequences) means record boundaries are lost: the
// reader marks the ring corrupt and returns the same error from then on (the daemon answers
// every later step of the session with it; other sessions are untouched).

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "far/base/result.h"
#include "far/protocol/ring_layout.h"

namespace far::protocol {

namespace internal {
struct MappedRange;
}  // namespace internal

/// One process's view of one ring: its bytes and its two indices, as addresses in this
/// process. Aliased: the memory must outlive every RingWriter/RingReader made from it.
struct RingRegion {
  uint8_t* data = nullptr;                       ///< `capacity` bytes
  uint64_t capacity = 0;                         ///< bytes; IsValidRingCapacity
  std::atomic<uint64_t>* write_index = nullptr;  ///< published by the producer
  std::atomic<uint64_t>* read_index = nullptr;   ///< published by the consumer
  internal::MappedRange* mapping = nullptr;      ///< the shm mapping (SIGBUS guard); null: none
  std::string name = "ring";                     ///< "update ring" or "reply ring", for messages
};

/// Where a record went.
struct RecordPosition {
  uint64_t sequence = 0;  ///< 1, 2, 3, ... per ring
  uint64_t index = 0;     ///< ring byte index (total bytes before it) of its first byte
  uint64_t size = 0;      ///< total bytes, header and padding included
};

/// The producer side. Starts on a fresh ring (index 0, first sequence 1).
/// Thread safety: one thread at a time.
class RingWriter {
 public:
  explicit RingWriter(RingRegion region);

  /// Appends a record: a RecordHeader (written here), the concatenation of `body` parts
  /// (everything after the header), then zero padding to a multiple of 8 bytes; then
  /// publishes the write index (release), so the consumer sees the whole record or nothing.
  /// Never blocks. Errors: kBusy when the free space is too small now (try again after the
  /// consumer moved on), kLimitExceeded when the record is larger than the ring (or than
  /// 2^32 - 8 bytes), kParseError when the consumer's published index is inconsistent or the
  /// segment was truncated.
  Result<RecordPosition> Write(RecordType type,
                               std::initializer_list<std::span<const uint8_t>> body);

  /// As Write, but while the ring is full retries (sleeping 50 us to 1 ms between tries)
  /// until `timeout`; kTimeout then, naming the bytes needed and free.
  Result<RecordPosition> WriteWait(RecordType type,
                                   std::initializer_list<std::span<const uint8_t>> body,
                                   std::chrono::milliseconds timeout);

  /// Sequence of the last record written; 0 before the first.
  uint64_t last_sequence() const { return next_sequence_ - 1; }
  /// Bytes written since the ring was created.
  uint64_t write_index() const { return write_index_; }
  uint64_t capacity() const { return region_.capacity; }

 private:
  RingRegion region_;
  uint64_t write_index_ = 0;
  uint64_t next_sequence_ = 1;
};

/// A record copied out of the ring.
struct RawRecord {
  RecordHeader header{};       ///< the checked header (the first copy)
  uint64_t index = 0;          ///< ring byte index of its first byte
  std::vector<uint8_t> bytes;  ///< private copy of the whole record; its first 16 bytes are
                               ///< `header` (not what shared memory holds now)
};

/// The consumer side. Starts on a fresh ring. Thread safety: one thread at a time.
class RingReader {
 public:
  /// `max_record_bytes` bounds every record (and so every private copy).
  RingReader(RingRegion region, uint64_t max_record_bytes);

  /// Copies the records with sequences last_sequence()+1 .. up_to_sequence out of the ring,
  /// then publishes the read index (the space is free again for the producer).
  /// up_to_sequence == last_sequence() returns nothing. Errors:
  ///  - kInvalidArgument, ring unchanged: up_to_sequence < last_sequence(), or the ring holds
  ///    fewer records than asked for ("... not committed: the ring holds records up to 9");
  ///  - kParseError, ring corrupt from now on: write index backwards or more than a capacity
  ///    ahead, a record header cut by the write index, size < 16, not a multiple of 8, past the
  ///    write index or over max_record_bytes, a sequence out of order, a truncated segment;
  ///    the message names the ring, record sequence and index, field and value.
  Result<std::vector<RawRecord>> ReadUpTo(uint64_t up_to_sequence);

  /// Copies the next record if the producer has committed one (nullopt otherwise) and
  /// publishes the read index. Errors: as ReadUpTo (kParseError, ring corrupt).
  Result<std::optional<RawRecord>> ReadNext();

  /// Sequence of the last record read; 0 before the first.
  uint64_t last_sequence() const { return last_sequence_; }
  uint64_t read_index() const { return read_index_; }
  bool corrupt() const { return corrupt_.has_value(); }
  uint64_t capacity() const { return region_.capacity; }

  /// Tests only: called after a record's header was copied and checked, before its bytes are
  /// copied (to overwrite shared memory in between).
  void SetCopyHookForTesting(std::function<void(const RecordHeader&)> hook) {
    copy_hook_ = std::move(hook);
  }

 private:
  // Copies and checks one record at `index` given the producer's index `write`.
  Result<RawRecord> CopyRecord(uint64_t index, uint64_t write, uint64_t expected_sequence);
  // Loads and checks the producer's index.
  Result<uint64_t> LoadWriteIndex();
  Error Corrupt(Error error);

  RingRegion region_;
  uint64_t max_record_bytes_;
  uint64_t read_index_ = 0;
  uint64_t last_sequence_ = 0;
  std::optional<Error> corrupt_;
  std::function<void(const RecordHeader&)> copy_hook_;
};

}  // namespace far::protocol
