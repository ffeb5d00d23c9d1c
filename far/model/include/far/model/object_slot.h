#pragma once

// Drake's Id vs Index: an object's id is the user's name for it, kept from the scene file to the
// reply; inside a pipeline's step an object is its slot, a dense index that the scene cache hands
// out when the object is added and reuses after it is removed. Every stage of a step
// (sweep-and-prune, the hierarchy and exact stages, the GPU culler, FCL) indexes its arrays by
// slot, and ids come back once, where the step's result is filled (slot_ids.h).

#include <cstddef>
#include <cstdint>

namespace far {

/// An object's slot in a pipeline: a dense index, valid from the step's world refresh to the
/// next update. A strong type: a slot is not an id, and neither converts to the other.
enum class ObjectSlot : uint32_t {};

/// The slot's position in arrays indexed by slot.
constexpr size_t Index(ObjectSlot slot) { return static_cast<size_t>(slot); }
/// The slot at position `index` of such an array.
constexpr ObjectSlot SlotAt(size_t index) { return static_cast<ObjectSlot>(index); }

}  // namespace far
