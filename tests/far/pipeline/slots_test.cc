// Inside a step objects are slots (far/model/object_slot.h), handed out in the order objects are
// added and reused after removals; a step answers by id, sorted. Whatever the slots, the answer
// must be the one the brute-force reference gives by id, and the same as a pipeline whose slots
// follow the ids.

#include <algorithm>
#include <vector>

#include "cpu_pipeline.h"
#include "test_scenes.h"
#include <gtest/gtest.h>

#include "far/pipeline/pipeline.h"

namespace far {
namespace {

using testing::CpuPipeline;

void Add(Pipeline& pipeline, const SceneObject& object) {
  ASSERT_TRUE(pipeline.AddObject(object.id, object.mesh, object.motion, object.X_WO).ok());
}

StepResult Step(Pipeline& pipeline, Method method, Output output) {
  StepRequest request;
  request.method = method;
  request.output = output;
  if (output == Output::kDistancePairs) request.distance = 0.05;
  auto result = pipeline.Step(request);
  EXPECT_TRUE(result.ok()) << ToString(result.error());
  return result.ok() ? std::move(*result) : StepResult{};
}

// Sorted, and every pair with its smaller id first.
template <typename Pair>
void ExpectSortedById(const std::vector<Pair>& pairs) {
  EXPECT_TRUE(std::is_sorted(pairs.begin(), pairs.end()));
  for (const Pair& pair : pairs) {
    if constexpr (requires { pair.pair; }) {
      EXPECT_LT(pair.pair.object_a, pair.pair.object_b);
    } else {
      EXPECT_LT(pair.object_a, pair.object_b);
    }
  }
}

TEST(SlotsTest, AnswersAreByIdWhateverOrderTheObjectsCameIn) {
  ThreadPool pool(2);
  // Ids scattered over uint32 (the largest included), added in descending order, then half of
  // them removed and added back, so that slots run against the ids and are reused.
  std::vector<SceneObject> objects = testing::RandomSoup(7, 10, 40, 1.5, 0.4);
  const uint32_t ids[] = {UINT32_MAX, 3000000000u, 77, 5, 4, 123456, 0, 9, 2000000000u, 31};
  for (size_t i = 0; i < objects.size(); ++i) objects[i].id = ids[i];
  auto descending = CpuPipeline();
  auto ascending = CpuPipeline();
  ASSERT_TRUE(descending && ascending);
  std::vector<SceneObject> by_id = objects;
  std::sort(by_id.begin(), by_id.end(),
            [](const SceneObject& a, const SceneObject& b) { return a.id < b.id; });
  for (auto it = by_id.rbegin(); it != by_id.rend(); ++it) Add(*descending, *it);
  for (size_t i = 0; i < by_id.size(); i += 2)
    ASSERT_TRUE(descending->RemoveObject(by_id[i].id).ok());
  for (size_t i = 0; i < by_id.size(); i += 2) Add(*descending, by_id[i]);
  for (const SceneObject& object : by_id) Add(*ascending, object);

  const testing::ReferencePairs reference = testing::ReferenceAnswer(objects, 0.05, pool);
  ASSERT_FALSE(reference.contacts.empty());
  for (Method method : {Method::kBvh, Method::kAabb, Method::kExact}) {
    for (Output output : {Output::kObjectPcs, Output::kObjectPairs, Output::kPrimitivePcs,
                          Output::kContacts, Output::kDistancePairs}) {
      SCOPED_TRACE(std::string(ToString(method)) + " " + std::string(ToString(output)));
      const StepResult mixed = Step(*descending, method, output);
      const StepResult ordered = Step(*ascending, method, output);
      EXPECT_TRUE(std::is_sorted(mixed.pcs_objects.begin(), mixed.pcs_objects.end()));
      ExpectSortedById(mixed.object_pairs);
      ExpectSortedById(mixed.contacts);
      ExpectSortedById(mixed.distance_pairs);
      EXPECT_EQ(mixed.pcs_objects, ordered.pcs_objects);
      EXPECT_EQ(mixed.object_pairs, ordered.object_pairs);
      EXPECT_EQ(mixed.pcs_primitives, ordered.pcs_primitives);
      EXPECT_EQ(mixed.contacts, ordered.contacts);
      EXPECT_EQ(mixed.distance_pairs, ordered.distance_pairs);
      if (output == Output::kContacts) {
        EXPECT_EQ(mixed.contacts, reference.contacts);
      }
      if (output == Output::kDistancePairs) {
        EXPECT_EQ(mixed.distance_pairs, reference.distance_pairs);
        // The same distances bit for bit, whichever object of a pair has the smaller slot.
        for (size_t i = 0; i < mixed.distance_pairs.size(); ++i) {
          EXPECT_EQ(mixed.distance_pairs[i].distance, ordered.distance_pairs[i].distance);
        }
      }
    }
  }
}

}  // namespace
}  // namespace far
