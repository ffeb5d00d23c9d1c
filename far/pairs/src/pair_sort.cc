#include "far/pairs/internal/pair_sort.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <utility>

namespace far::internal {
namespace {

const SlotContact& PairOf(const SlotContact& p) { return p; }
const SlotContact& PairOf(const SlotDistancePair& p) { return p.pair; }

// The four sort keys of a pair, last field first.
constexpr int kKeys = 4;
uint32_t Key(const SlotContact& p, int k) {
  switch (k) {
    case 0:
      return p.triangle_b;
    case 1:
      return static_cast<uint32_t>(p.object_b);
    case 2:
      return p.triangle_a;
    default:
      return static_cast<uint32_t>(p.object_a);
  }
}

// Below this many pairs the counting passes cost more than a comparison sort.
constexpr size_t kRadixMinimum = 128;

// A least significant digit radix sort over the four fields, last field first, 8 bits per
// pass, each pass a stable counting sort; passes over bits no element sets are skipped (object
// slots and triangle indices are small, so a sort takes a few passes, not sixteen).
template <typename T>
void RadixSort(std::vector<T>& items) {
  std::vector<T> scratch(items.size());
  for (int k = 0; k < kKeys; ++k) {
    uint32_t bits = 0;
    for (const T& item : items) bits |= Key(PairOf(item), k);
    for (uint32_t shift = 0; shift < std::bit_width(bits); shift += 8) {
      std::array<size_t, 256> start{};
      for (const T& item : items) ++start[(Key(PairOf(item), k) >> shift) & 0xff];
      size_t sum = 0;
      for (size_t& s : start) sum += std::exchange(s, sum);
      for (const T& item : items) scratch[start[(Key(PairOf(item), k) >> shift) & 0xff]++] = item;
      items.swap(scratch);
    }
  }
}

template <typename T>
void Sort(std::vector<T>& items) {
  if (items.size() < kRadixMinimum) {
    std::stable_sort(items.begin(), items.end(),
                     [](const T& x, const T& y) { return PairOf(x) < PairOf(y); });
  } else {
    RadixSort(items);
  }
}

}  // namespace

void SortPairs(std::vector<SlotContact>& pairs) { Sort(pairs); }
void SortPairs(std::vector<SlotDistancePair>& pairs) { Sort(pairs); }

}  // namespace far::internal
