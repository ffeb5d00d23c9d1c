#include "piece_buffers.h"

#include <algorithm>

#include "draw_pacer.h"

namespace far::internal {
namespace {

using DrawCommand = PieceBuffers::DrawCommand;

GLsizei CornerCount(PieceSet set) {
  return static_cast<GLsizei>(CornerIndices(ShapeOf(set)).size());
}

}  // namespace

PieceBuffers::PieceBuffers() {
  for (Shape shape : {Shape::kBox, Shape::kPrism, Shape::kTriangle}) {
    const auto indices = CornerIndices(shape);
    GLuint& buffer = index_buffers_[static_cast<size_t>(shape)];
    glCreateBuffers(1, &buffer);
    glNamedBufferStorage(buffer, static_cast<GLsizeiptr>(indices.size()), indices.data(), 0);
  }
  // One instance per draw instance: four vec3 (p0..p3), then triangle and slot.
  for (int set = 0; set < kNumPieceSets; ++set) {
    Store& s = stores_[static_cast<size_t>(set)];
    glCreateBuffers(1, &s.buffer);
    glCreateBuffers(1, &s.indirect_buffer);
    glCreateVertexArrays(1, &s.vao);
    glVertexArrayElementBuffer(
        s.vao, index_buffers_[static_cast<size_t>(ShapeOf(static_cast<PieceSet>(set)))]);
    glVertexArrayVertexBuffer(s.vao, 0, s.buffer, 0, sizeof(PieceInstance));
    glVertexArrayBindingDivisor(s.vao, 0, 1);
    for (GLuint i = 0; i < 4; ++i) {
      glEnableVertexArrayAttrib(s.vao, i);
      glVertexArrayAttribFormat(s.vao, i, 3, GL_FLOAT, GL_FALSE, i * 12);
      glVertexArrayAttribBinding(s.vao, i, 0);
    }
    for (GLuint i = 4; i < 6; ++i) {
      glEnableVertexArrayAttrib(s.vao, i);
      glVertexArrayAttribIFormat(s.vao, i, 1, GL_UNSIGNED_INT, 48 + (i - 4) * 4);
      glVertexArrayAttribBinding(s.vao, i, 0);
    }
  }
}

PieceBuffers::~PieceBuffers() {
  for (Store& s : stores_) {
    glDeleteBuffers(1, &s.buffer);
    glDeleteBuffers(1, &s.indirect_buffer);
    glDeleteVertexArrays(1, &s.vao);
  }
  glDeleteBuffers(kNumShapes, index_buffers_.data());
}

void PieceBuffers::SetPieces(PieceSet set, uint32_t slot, std::vector<PieceInstance> pieces) {
  Store& s = store(set);
  if (slot >= s.slots.size()) {
    s.slots.resize(slot + 1);
    s.footprint_sums.resize(slot + 1);
    s.dirty.resize(slot + 1, 0);
    s.layout_changed = true;
  }
  if (s.slots[slot].size() != pieces.size()) s.layout_changed = true;
  std::vector<PieceFootprint>& sums = s.footprint_sums[slot];
  sums.assign(1, PieceFootprint{});
  PieceFootprint sum;
  for (size_t i = 0; i < pieces.size(); ++i) {
    sum += FootprintOf(set, pieces[i]);
    if ((i + 1) % kFootprintBlock == 0) sums.push_back(sum);
  }
  s.slots[slot] = std::move(pieces);
  s.dirty[slot] = 1;
}

void PieceBuffers::RemoveSlot(uint32_t slot) {
  for (Store& s : stores_) {
    if (slot < s.slots.size() && !s.slots[slot].empty()) {
      s.slots[slot].clear();
      s.footprint_sums[slot].assign(1, PieceFootprint{});
      s.layout_changed = true;
    }
  }
}

size_t PieceBuffers::num_slots() const {
  size_t n = 0;
  for (const Store& s : stores_) n = std::max(n, s.slots.size());
  return n;
}

namespace {

// Uploads `count` instances to `buffer` at instance `at`, in parts with the pacer's pauses
// between them; false when it said stop.
bool Upload(GLuint buffer, uint64_t at, const PieceInstance* instances, uint64_t count,
            DrawPacer& pacer, RenderCounters* counters) {
  constexpr uint64_t kPart = (4u << 20) / sizeof(PieceInstance);  // 4 MiB
  for (uint64_t done = 0; done < count; done += kPart) {
    const uint64_t n = std::min(kPart, count - done);
    glNamedBufferSubData(buffer, static_cast<GLintptr>((at + done) * sizeof(PieceInstance)),
                         static_cast<GLsizeiptr>(n * sizeof(PieceInstance)), instances + done);
    counters->bytes_uploaded += static_cast<int64_t>(n * sizeof(PieceInstance));
    pacer.MaybePause();
    if (pacer.stopped() != StopReason::kNone) return false;
  }
  return true;
}

}  // namespace

bool PieceBuffers::Sync(PieceSet set, DrawPacer& pacer, RenderCounters* counters) {
  Store& s = store(set);
  if (s.layout_changed) {
    // New sizes: a new buffer, every slot uploaded. Stopped half-way, the layout stays changed.
    s.first.assign(s.slots.size(), 0);
    s.total = 0;
    for (size_t slot = 0; slot < s.slots.size(); ++slot) {
      s.first[slot] = s.total;
      s.total += s.slots[slot].size();
    }
    const auto bytes = static_cast<GLsizeiptr>(s.total * sizeof(PieceInstance));
    glNamedBufferData(s.buffer, std::max<GLsizeiptr>(bytes, 1), nullptr, GL_STATIC_DRAW);
    for (size_t slot = 0; slot < s.slots.size(); ++slot) {
      if (!Upload(s.buffer, s.first[slot], s.slots[slot].data(), s.slots[slot].size(), pacer,
                  counters)) {
        return false;
      }
    }
  } else {
    for (size_t slot = 0; slot < s.slots.size(); ++slot) {
      if (!s.dirty[slot] || s.slots[slot].empty()) continue;
      if (!Upload(s.buffer, s.first[slot], s.slots[slot].data(), s.slots[slot].size(), pacer,
                  counters)) {
        return false;
      }
      s.dirty[slot] = 0;
    }
  }
  std::fill(s.dirty.begin(), s.dirty.end(), 0);
  s.layout_changed = false;
  return true;
}

void PieceBuffers::PrepareViewDraws(PieceSet set, std::span<const ViewObject> objects,
                                    std::span<const uint8_t> alive, int triangles_per_primitive,
                                    int64_t* bytes) {
  Store& s = store(set);
  std::vector<DrawCommand>& commands = s.commands;
  commands.clear();
  // Runs longer than kMaxCommandInstances are cut into several commands.
  const auto add = [&](uint64_t first, uint64_t count) {
    for (uint64_t at = first; at < first + count; at += kMaxCommandInstances) {
      const uint64_t n = std::min(kMaxCommandInstances, first + count - at);
      commands.push_back({static_cast<GLuint>(CornerCount(set)), static_cast<GLuint>(n), 0, 0,
                          static_cast<GLuint>(at)});
    }
  };
  for (const ViewObject& object : objects) {
    if (object.slot >= s.slots.size() || s.slots[object.slot].empty()) continue;
    if (triangles_per_primitive <= 0) {
      if (alive[object.first_primitive]) add(s.first[object.slot], s.slots[object.slot].size());
      continue;
    }
    // One command per run of live sub-objects: pruned ones are not drawn at all.
    const auto k = static_cast<uint32_t>(triangles_per_primitive);
    const uint32_t primitives = (object.num_triangles + k - 1) / k;
    for (uint32_t j = 0; j < primitives;) {
      if (!alive[object.first_primitive + j]) {
        ++j;
        continue;
      }
      uint32_t end = j + 1;
      while (end < primitives && alive[object.first_primitive + end]) ++end;
      const auto [first, count_begin] = PrimitiveRange(set, object, triangles_per_primitive, j);
      const auto [last, count_last] = PrimitiveRange(set, object, triangles_per_primitive, end - 1);
      add(first, last + count_last - first);
      (void)count_begin;
      j = end;
    }
  }
  glNamedBufferData(
      s.indirect_buffer,
      static_cast<GLsizeiptr>(std::max<size_t>(commands.size(), 1) * sizeof(DrawCommand)),
      commands.data(), GL_STREAM_DRAW);
  *bytes += static_cast<int64_t>(commands.size() * sizeof(DrawCommand));
}

std::pair<uint64_t, uint64_t> PieceBuffers::ViewCommand(PieceSet set, size_t i) const {
  const DrawCommand& command = store(set).commands[i];
  return {command.base_instance, command.instance_count};
}

void PieceBuffers::DrawViewCommands(PieceSet set, size_t begin, size_t end,
                                    RenderCounters* counters) {
  const Store& s = store(set);
  if (begin >= end) return;
  glBindVertexArray(s.vao);
  glBindBuffer(GL_DRAW_INDIRECT_BUFFER, s.indirect_buffer);
  glMultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_BYTE,
                              reinterpret_cast<const void*>(begin * sizeof(DrawCommand)),
                              static_cast<GLsizei>(end - begin), 0);
  counters->draws++;
  for (size_t i = begin; i < end; ++i) counters->instances += s.commands[i].instance_count;
}

void PieceBuffers::Draw(PieceSet set, uint64_t first, uint64_t count, RenderCounters* counters) {
  if (count == 0) return;
  glBindVertexArray(store(set).vao);
  glDrawElementsInstancedBaseInstance(GL_TRIANGLES, CornerCount(set), GL_UNSIGNED_BYTE, nullptr,
                                      static_cast<GLsizei>(count), static_cast<GLuint>(first));
  counters->draws++;
  counters->instances += static_cast<int64_t>(count);
}

PieceFootprint PieceBuffers::Footprint(PieceSet set, uint64_t first, uint64_t count) const {
  const Store& s = store(set);
  // The slot holding `first`: the last one that starts at or before it (empty ones start where
  // the next does, and hold nothing).
  const auto after = std::upper_bound(s.first.begin(), s.first.end(), first);
  if (count == 0 || after == s.first.begin()) return {};
  const auto slot = static_cast<size_t>(after - s.first.begin() - 1);
  const uint64_t begin = first - s.first[slot];
  const uint64_t end = std::min<uint64_t>(begin + count, s.slots[slot].size());
  if (begin >= end) return {};
  return FootprintPrefix(set, slot, end) - FootprintPrefix(set, slot, begin);
}

PieceFootprint PieceBuffers::FootprintPrefix(PieceSet set, size_t slot, uint64_t count) const {
  const Store& s = store(set);
  const uint64_t block = count / kFootprintBlock;
  PieceFootprint sum = s.footprint_sums[slot][block];
  for (uint64_t i = block * kFootprintBlock; i < count; ++i)
    sum += FootprintOf(set, s.slots[slot][i]);
  return sum;
}

std::pair<uint64_t, uint64_t> PieceBuffers::PrimitiveRange(PieceSet set, const ViewObject& object,
                                                           int triangles_per_primitive,
                                                           int local) const {
  const Store& s = store(set);
  const uint64_t per = static_cast<uint64_t>(InstancesPerTriangle(set));
  uint64_t first = s.first[object.slot], count = s.slots[object.slot].size();
  if (triangles_per_primitive > 0) {
    const uint64_t k = static_cast<uint64_t>(triangles_per_primitive);
    const uint64_t begin = static_cast<uint64_t>(local) * k * per;
    count = std::min(count - std::min(count, begin), k * per);
    first += begin;
  }
  return {first, count};
}

}  // namespace far::internal
