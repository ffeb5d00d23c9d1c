#include "far/pairs/internal/pair_sort.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <utility>

namespace far::internal {
namespace {

const ContactPair& PairOf(const ContactPair& p) { return p; }
const ContactPair& PairOf(const DistancePair& p) { return p.pair; }

// Below this many pairs the counting passes cost more than a comparison sort.
constexpr size_t kRadixMinimum = 128;

// A least significant digit radix sort over the four fields, last field first, 8 bits per
// pass, each pass a stable counting sort; passes over bits no element sets are skipped (object
// ids and triangle indices are small, so a sort takes a few passes, not sixteen).
template <typename T>
void RadixSort(std::vector<T>& items) {
  using Field = uint32_t ContactPair::*;
  constexpr std::array<Field, 4> kFields = {&ContactPair::triangle_b, &ContactPair::object_b,
                                            &ContactPair::triangle_a, &ContactPair::object_a};
  std::vector<T> scratch(items.size());
  for (const Field field : kFields) {
    uint32_t bits = 0;
    for (const T& item : items) bits |= PairOf(item).*field;
    for (uint32_t shift = 0; shift < std::bit_width(bits); shift += 8) {
      std::array<size_t, 256> start{};
      for (const T& item : items) ++start[(PairOf(item).*field >> shift) & 0xff];
      size_t sum = 0;
      for (size_t& s : start) sum += std::exchange(s, sum);
      for (const T& item : items) scratch[start[(PairOf(item).*field >> shift) & 0xff]++] = item;
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

void SortPairs(std::vector<ContactPair>& pairs) { Sort(pairs); }
void SortPairs(std::vector<DistancePair>& pairs) { Sort(pairs); }

}  // namespace far::internal
