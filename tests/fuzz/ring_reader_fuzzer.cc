// Fuzz target ring_reader: a hostile client's shared-memory segment as far-daemon reads it. One
// real session segment (ShmSegment::Create: a sealed memfd with 64 KiB rings, as
// SessionRegistry makes them) is reset for every input; the input then plays the client,
// writing any bytes into the update ring and publishing any indices, while the daemon's side
// runs what a session worker runs: UpdateReader::Drain (RingReader framing, ParseUpdateRecord)
// with the daemon's default RingLimits, then SceneModel::Apply within the daemon's default
// session limits and its daemon-wide budget; and the reply ring's writer (WriteShmReply)
// against any read index the client publishes.
//
// Input: operations until the bytes run out, each a uint8 `op % 4` then (little-endian)
//   0 poke     uint16 offset, uint16 length, bytes: written into the update ring at
//              offset, wrapping at its end
//   1 publish  uint64: the update ring's write index (the client's to publish)
//   2 drain    uint64 up_to_sequence: the daemon drains and applies, as for a step request
//   3 reply    uint64: the reply ring's read index (the client's), uint16 length, bytes: the
//              daemon writes them as a step reply record
//
// Oracles besides the sanitizers: a drain returns exactly the records last+1 .. up_to in
// order; a corrupt ring stays corrupt (every later drain fails).

#include <cstdint>
#include <cstring>
#include <memory>

#include "daemon_config.h"
#include "fuzz_input.h"
#include <spdlog/spdlog.h>

#include "far/model/scene_budget.h"
#include "far/model/scene_model.h"
#include "far/protocol/ring_records.h"
#include "far/protocol/shm_reply.h"
#include "far/protocol/shm_segment.h"

namespace far::fuzz {
namespace {

constexpr uint64_t kCapacity = protocol::kMinRingCapacity;

// One segment for the whole run (creating one per input would fuzz memfd_create, not far).
protocol::ShmSegment& Segment() {
  static const std::unique_ptr<protocol::ShmSegment> segment = [] {
    auto created = protocol::ShmSegment::Create(1, {kCapacity, kCapacity});
    FAR_FUZZ_CHECK(created);
    return std::move(*created);
  }();
  return *segment;
}

// A fresh session's segment: both rings zero, all four indices zero.
void Reset(const protocol::RingRegion& update, const protocol::RingRegion& reply) {
  for (const auto* ring : {&update, &reply}) {
    std::memset(ring->data, 0, ring->capacity);
    ring->write_index->store(0);
    ring->read_index->store(0);
  }
}

void Poke(const protocol::RingRegion& ring, uint64_t offset, std::span<const uint8_t> bytes) {
  for (size_t i = 0; i < bytes.size(); ++i)
    ring.data[(offset + i) & (ring.capacity - 1)] = bytes[i];
}

// The daemon's session state for one input.
struct DaemonSide {
  server::DaemonConfig config;
  protocol::UpdateReader updates;
  protocol::RingWriter replies;
  SharedSceneBudget budget{config.max_vertices_total, config.max_triangles_total};
  bool admitted = budget.Admit(1, 0, {}).ok();  // the session's holder
  SceneModel scene;

  DaemonSide(const protocol::RingRegion& update, const protocol::RingRegion& reply)
      : updates(update, server::RingLimitsOf(config)),
        replies(reply),
        scene(server::SceneLimitsOf(config), &budget, 1) {}

  void Drain(uint64_t up_to) {
    const bool was_corrupt = updates.corrupt();
    const uint64_t first = updates.last_sequence() + 1;
    auto drained = updates.Drain(up_to);
    if (was_corrupt) FAR_FUZZ_CHECK(!drained && updates.corrupt());
    if (!drained) return;
    FAR_FUZZ_CHECK(updates.last_sequence() == up_to);
    FAR_FUZZ_CHECK(drained->size() == up_to + 1 - first);
    for (size_t i = 0; i < drained->size(); ++i)
      FAR_FUZZ_CHECK((*drained)[i].sequence == first + i);
    std::vector<SceneUpdate> batch;
    for (auto& [sequence, update] : *drained) batch.push_back(std::move(update));
    (void)scene.Apply(batch);
  }
};

}  // namespace
}  // namespace far::fuzz

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  spdlog::set_level(spdlog::level::off);
  (void)far::fuzz::Segment();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace far::fuzz;
  const far::protocol::RingRegion update = Segment().update_ring();
  const far::protocol::RingRegion reply = Segment().reply_ring();
  Reset(update, reply);
  DaemonSide daemon(update, reply);
  FuzzInput in(data, size);
  while (!in.empty()) {
    switch (in.Take<uint8_t>() % 4) {
      case 0: {
        const uint16_t offset = in.Take<uint16_t>();
        Poke(update, offset, in.TakeBytes(in.Take<uint16_t>()));
        break;
      }
      case 1:
        update.write_index->store(in.Take<uint64_t>());
        break;
      case 2:
        daemon.Drain(in.Take<uint64_t>());
        break;
      default: {
        reply.read_index->store(in.Take<uint64_t>());
        (void)far::protocol::WriteShmReply(daemon.replies, in.TakeBytes(in.Take<uint16_t>()));
        break;
      }
    }
  }
  return 0;
}
