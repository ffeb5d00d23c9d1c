#include "far/model/slot_ids.h"

#include <vector>

#include <gtest/gtest.h>

namespace far {
namespace {

TEST(SlotIdsTest, PairsComeBackByIdWithTheSmallerIdFirst) {
  // Slot 0 holds id 9, slot 1 id 4, slot 2 id 7: slot order is not id order.
  const std::vector<uint32_t> id_of_slot = {9, 4, 7};
  const SlotIds ids(id_of_slot);
  const ObjectSlot s0 = SlotAt(0), s1 = SlotAt(1), s2 = SlotAt(2);
  EXPECT_EQ(ids(s1), 4u);
  EXPECT_EQ(ids.WithIds(SlotPair{s0, s1}), (ObjectPair{4, 9}));
  // The triangles go with their objects when the sides swap.
  EXPECT_EQ(ids.WithIds(SlotContact{s0, 10, s1, 20}), (ContactPair{4, 20, 9, 10}));
  EXPECT_EQ(ids.WithIds(SlotContact{s1, 10, s2, 20}), (ContactPair{4, 10, 7, 20}));
  const DistancePair d = ids.WithIds(SlotDistancePair{{s0, 1, s2, 2}, 0.25});
  EXPECT_EQ(d.pair, (ContactPair{7, 2, 9, 1}));
  EXPECT_EQ(d.distance, 0.25);
}

TEST(SlotIdsTest, ListsComeBackSortedById) {
  const std::vector<uint32_t> id_of_slot = {9, 4, 7, UINT32_MAX};
  const SlotIds ids(id_of_slot);
  const ObjectSlot s0 = SlotAt(0), s1 = SlotAt(1), s2 = SlotAt(2), s3 = SlotAt(3);
  // Sorted by slot, as the stages answer.
  const std::vector<SlotContact> contacts = {
      {s0, 5, s1, 1}, {s0, 5, s3, 0}, {s1, 0, s2, 3}, {s2, 1, s3, 2}};
  EXPECT_EQ(ids.WithIds(contacts),
            (std::vector<ContactPair>{
                {4, 0, 7, 3}, {4, 1, 9, 5}, {7, 1, UINT32_MAX, 2}, {9, 5, UINT32_MAX, 0}}));
  const std::vector<SlotPair> pairs = {{s0, s1}, {s0, s2}, {s1, s2}};
  EXPECT_EQ(ids.WithIds(pairs), (std::vector<ObjectPair>{{4, 7}, {4, 9}, {7, 9}}));
  // Slots in id order: the order is kept as it is.
  const std::vector<uint32_t> ascending = {1, 5, 8};
  const std::vector<SlotPair> in_order = {{s0, s1}, {s0, s2}, {s1, s2}};
  EXPECT_EQ(SlotIds(ascending).WithIds(in_order),
            (std::vector<ObjectPair>{{1, 5}, {1, 8}, {5, 8}}));
  EXPECT_TRUE(ids.WithIds(std::vector<SlotPair>{}).empty());
}

}  // namespace
}  // namespace far
