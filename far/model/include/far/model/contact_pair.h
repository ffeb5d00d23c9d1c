#pragma once

#include <compare>
#include <cstdint>

namespace far {

/// A pair of triangles of two different objects, ordered so that object_a < object_b.
/// Triangle indices are as in the object's mesh file (see docs/scene-format.md).
struct ContactPair {
  uint32_t object_a = 0;
  uint32_t triangle_a = 0;
  uint32_t object_b = 0;
  uint32_t triangle_b = 0;
  auto operator<=>(const ContactPair&) const = default;
};

/// A pair of triangles closer than the query distance, with their distance in world units.
struct DistancePair {
  ContactPair pair;
  double distance = 0;
  bool operator==(const DistancePair& other) const { return pair == other.pair; }
  auto operator<=>(const DistancePair& other) const { return pair <=> other.pair; }
};

/// A pair of object ids, object_a < object_b.
struct ObjectPair {
  uint32_t object_a = 0;
  uint32_t object_b = 0;
  auto operator<=>(const ObjectPair&) const = default;
};

}  // namespace far
