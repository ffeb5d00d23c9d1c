#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "far/protocol/ring.h"
#include "far/protocol/ring_layout.h"

namespace far::protocol::testing {

// A ring in private memory: the test plays the other process by writing the bytes directly.
struct TestRing {
  explicit TestRing(uint64_t capacity, std::string ring_name = "test ring")
      : data(capacity, 0), name(std::move(ring_name)) {}
  RingRegion region() {
    RingRegion r;
    r.data = data.data();
    r.capacity = data.size();
    r.write_index = &write_index;
    r.read_index = &read_index;
    r.name = name;
    return r;
  }
  // Writes raw bytes into the byte stream at `index` (wrapping), as a hostile producer would.
  void Poke(uint64_t index, const void* bytes, size_t size) {
    const auto* in = static_cast<const uint8_t*>(bytes);
    for (size_t i = 0; i < size; ++i) data[(index + i) & (data.size() - 1)] = in[i];
  }
  void PokeHeader(uint64_t index, uint32_t type, uint32_t size, uint64_t sequence) {
    const RecordHeader header{type, size, sequence};
    Poke(index, &header, sizeof(header));
  }
  // Appends forged record bytes at the write index and commits them, as a hostile client.
  void Append(const std::vector<uint8_t>& record) {
    const uint64_t at = write_index.load();
    Poke(at, record.data(), record.size());
    write_index = at + record.size();
  }
  std::vector<uint8_t> data;
  std::string name;
  std::atomic<uint64_t> write_index{0};
  std::atomic<uint64_t> read_index{0};
};

}  // namespace far::protocol::testing
