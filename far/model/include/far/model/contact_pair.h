#pragma once

#include <compare>
#include <cstdint>

#include "far/model/object_slot.h"

namespace far {

/// A pair of triangles of two different objects, ordered so that object_a < object_b.
/// Triangle indices are as in the object's mesh file (see docs/scene-format.md). `Object` names
/// the objects: their ids (ContactPair, what a step answers) or, inside a step, their slots
/// (SlotContact, see object_slot.h).
template <typename Object>
struct BasicContactPair {
  Object object_a{};
  uint32_t triangle_a = 0;
  Object object_b{};
  uint32_t triangle_b = 0;
  auto operator<=>(const BasicContactPair&) const = default;
};

/// A pair of triangles closer than the query distance, with their distance in world units.
template <typename Object>
struct BasicDistancePair {
  BasicContactPair<Object> pair;
  double distance = 0;
  bool operator==(const BasicDistancePair& other) const { return pair == other.pair; }
  auto operator<=>(const BasicDistancePair& other) const { return pair <=> other.pair; }
};

/// A pair of objects, object_a < object_b.
template <typename Object>
struct BasicObjectPair {
  Object object_a{};
  Object object_b{};
  auto operator<=>(const BasicObjectPair&) const = default;
};

/// What a step answers: objects by id.
using ContactPair = BasicContactPair<uint32_t>;
using DistancePair = BasicDistancePair<uint32_t>;
using ObjectPair = BasicObjectPair<uint32_t>;

/// Inside a step: objects by slot.
using SlotContact = BasicContactPair<ObjectSlot>;
using SlotDistancePair = BasicDistancePair<ObjectSlot>;
using SlotPair = BasicObjectPair<ObjectSlot>;

}  // namespace far
