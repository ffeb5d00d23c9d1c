#include "far/pairs/internal/pair_sort.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <optional>
#include <utility>

namespace far::internal {
namespace {

const SlotContact& PairOf(const SlotContact& p) { return p; }
const SlotContact& PairOf(const SlotDistancePair& p) { return p.pair; }

// The four fields of a pair, most significant first.
constexpr int kFields = 4;
uint32_t Field(const SlotContact& p, int k) {
  switch (k) {
    case 0:
      return static_cast<uint32_t>(p.object_a);
    case 1:
      return p.triangle_a;
    case 2:
      return static_cast<uint32_t>(p.object_b);
    default:
      return p.triangle_b;
  }
}

// Below this many pairs the counting passes cost more than a comparison sort.
constexpr size_t kRadixMinimum = 128;

// A pair packed into one integer with the same order: each field in as many bits as the
// largest value of that field among the pairs needs, object_a highest. Slots and triangle
// indices are small, so a step's pairs fit in 64 bits (paper-leaves: 8 + 15 + 8 + 15 bits).
struct PackedLayout {
  std::array<int, kFields> shift{};
  int bits = 0;

  static std::optional<PackedLayout> For(const auto& items) {
    std::array<uint32_t, kFields> used{};
    for (const auto& item : items) {
      for (int k = 0; k < kFields; ++k) used[k] |= Field(PairOf(item), k);
    }
    PackedLayout layout;
    for (int k = kFields; k-- > 0;) {
      layout.shift[k] = layout.bits;
      layout.bits += std::bit_width(used[k]);
    }
    if (layout.bits > 64) return std::nullopt;
    return layout;
  }
  uint64_t Pack(const SlotContact& p) const {
    uint64_t key = 0;
    // A field above 64 bits of the others is always 0 (no shift of 64: undefined).
    for (int k = 0; k < kFields; ++k) key |= shift[k] < 64 ? uint64_t{Field(p, k)} << shift[k] : 0;
    return key;
  }
  SlotContact Unpack(uint64_t key) const {
    const auto field = [&](int k) {
      const int width = (k == 0 ? bits : shift[k - 1]) - shift[k];
      return static_cast<uint32_t>(width == 0 ? 0
                                              : (key >> shift[k]) & (~uint64_t{0} >> (64 - width)));
    };
    return {SlotAt(field(0)), field(1), SlotAt(field(2)), field(3)};
  }
};

// A least significant digit radix sort of `items` by key(item) < 2^bits, each pass a stable
// counting sort, every pass's counts taken in one read of the keys. Digits of 8 bits for a few
// thousand items, up to 11 (2048 counters, still in the L1 cache) for tens of thousands: wider
// digits mean fewer passes, but counters to clear and sum that a small sort does not repay.
template <typename T, typename KeyOf>
void RadixSortByKey(std::vector<T>& items, int bits, KeyOf key_of) {
  if (bits == 0) return;
  const int widest = std::clamp(static_cast<int>(std::bit_width(items.size())) - 4, 8, 11);
  const int passes = (bits + widest - 1) / widest;
  const int digit = (bits + passes - 1) / passes;
  const uint64_t mask = (uint64_t{1} << digit) - 1;
  std::vector<std::vector<size_t>> start(passes, std::vector<size_t>(size_t{1} << digit));
  for (const T& item : items) {
    const uint64_t key = key_of(item);
    for (int p = 0; p < passes; ++p) ++start[p][(key >> (p * digit)) & mask];
  }
  std::vector<T> scratch(items.size());
  for (int p = 0; p < passes; ++p) {
    size_t sum = 0;
    for (size_t& s : start[p]) sum += std::exchange(s, sum);
    for (const T& item : items) scratch[start[p][(key_of(item) >> (p * digit)) & mask]++] = item;
    items.swap(scratch);
  }
}

// Pairs whose fields fit 64 bits: their packed keys sorted (a key is the whole pair; a distance
// pair carries its distance beside it).
void SortPacked(std::vector<SlotContact>& pairs, const PackedLayout& layout) {
  std::vector<uint64_t> keys(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) keys[i] = layout.Pack(pairs[i]);
  RadixSortByKey(keys, layout.bits, [](uint64_t key) { return key; });
  for (size_t i = 0; i < pairs.size(); ++i) pairs[i] = layout.Unpack(keys[i]);
}
void SortPacked(std::vector<SlotDistancePair>& pairs, const PackedLayout& layout) {
  struct Entry {
    uint64_t key;
    double distance;
  };
  std::vector<Entry> entries(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i)
    entries[i] = {layout.Pack(pairs[i].pair), pairs[i].distance};
  RadixSortByKey(entries, layout.bits, [](const Entry& e) { return e.key; });
  for (size_t i = 0; i < pairs.size(); ++i)
    pairs[i] = {layout.Unpack(entries[i].key), entries[i].distance};
}

// Any pairs: field by field, the last field first, each field's bits in as many 11-bit passes
// as it needs (fields that never vary cost one read).
template <typename T>
void SortFieldByField(std::vector<T>& items) {
  for (int k = kFields; k-- > 0;) {
    uint32_t used = 0;
    for (const T& item : items) used |= Field(PairOf(item), k);
    RadixSortByKey(items, std::bit_width(used),
                   [k](const T& item) { return Field(PairOf(item), k); });
  }
}

template <typename T>
void Sort(std::vector<T>& items) {
  if (items.size() < kRadixMinimum) {
    std::stable_sort(items.begin(), items.end(),
                     [](const T& x, const T& y) { return PairOf(x) < PairOf(y); });
  } else if (const std::optional<PackedLayout> layout = PackedLayout::For(items)) {
    SortPacked(items, *layout);
  } else {
    SortFieldByField(items);
  }
}

}  // namespace

void SortPairs(std::vector<SlotContact>& pairs) { Sort(pairs); }
void SortPairs(std::vector<SlotDistancePair>& pairs) { Sort(pairs); }

}  // namespace far::internal
