// far::ComputeBatcher (label gpu; llvmpipe in CI): steps issued together in one batch answer
// exactly as each collider answers alone, a step whose output buffers overflow in the middle of
// a batch is run again with its own buffers, and pipelines on many threads stepping the gpu
// method through one batcher never miss a contact or a distance pair of the reference.
#include "far/gpu/compute_batcher.h"

#include <algorithm>
#include <chrono>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "test_scenes.h"
#include <Eigen/Core>
#include <gtest/gtest.h>

#include "far/base/thread_pool.h"
#include "far/gpu/gl_context.h"
#include "far/pairs/triangle_bvh.h"
#include "far/pipeline/pipeline.h"

namespace far {
namespace {

using Eigen::Vector3d;

// Objects of random triangles in one region, with their hierarchies, as a step's query.
struct BatchScene {
  std::vector<Mesh> meshes;
  std::vector<std::vector<ComputeNode>> nodes;
  std::vector<std::vector<uint32_t>> orders;
  std::vector<ComputeObject> objects;
  ComputeQuery query;

  // Every object's topology and world keys are its own (from the seed).
  BatchScene(uint64_t seed, int num_objects, int triangles, double slack, bool distance) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const auto point = [&](double scale) -> Vector3d {
      return Vector3d(u(rng), u(rng), u(rng)) * scale;
    };
    meshes.resize(num_objects);
    nodes.resize(num_objects);
    orders.resize(num_objects);
    for (int o = 0; o < num_objects; ++o) {
      for (int t = 0; t < triangles; ++t) {
        const Vector3d c = point(0.8);
        for (int k = 0; k < 3; ++k) meshes[o].p_MV.push_back(c + point(0.2));
        const auto first = static_cast<uint32_t>(3 * t);
        meshes[o].triangles.push_back({first, first + 1, first + 2});
      }
      TriangleBvh bvh;
      EXPECT_TRUE(bvh.Build(meshes[o].p_MV, meshes[o].triangles));
      for (const auto& node : bvh.nodes()) nodes[o].push_back({node.first, node.count});
      orders[o] = bvh.order();
    }
    for (int o = 0; o < num_objects; ++o) {
      const uint64_t key = 1000 * seed + static_cast<uint64_t>(o) + 1;
      // One pair box for all: every two objects are a pair.
      objects.push_back({meshes[o].p_MV, meshes[o].triangles, nodes[o], orders[o], key, key,
                         Eigen::AlignedBox3d(Vector3d::Zero(), Vector3d::Zero())});
    }
    query.objects = objects;
    query.slack = slack;
    query.distance = distance;
  }
};

// An answer in a form that compares whole: the pairs sorted (the GPU appends in any order).
using Canonical =
    std::tuple<std::vector<SlotPair>, std::vector<SlotContact>,
               std::vector<std::pair<SlotContact, uint8_t>>, std::vector<std::vector<uint32_t>>,
               int64_t>;

Canonical CanonicalOf(const ComputeAnswer& answer) {
  std::vector<SlotContact> crossing = answer.crossing;
  std::sort(crossing.begin(), crossing.end());
  std::vector<std::pair<SlotContact, uint8_t>> undecided;
  for (size_t i = 0; i < answer.undecided.size(); ++i)
    undecided.push_back({answer.undecided[i], answer.proven_apart[i]});
  std::sort(undecided.begin(), undecided.end());
  return {answer.object_pairs, crossing, undecided, answer.pcs, answer.box_pairs};
}

// Scenes for one batch; the last one has more undecided pairs (a distance query with a slack
// wider than the scene: every pair) than the output buffers first hold, so it overflows and runs
// again after the others were submitted.
std::vector<std::unique_ptr<BatchScene>> Scenes() {
  std::vector<std::unique_ptr<BatchScene>> scenes;
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    scenes.push_back(std::make_unique<BatchScene>(seed, 2 + static_cast<int>(seed % 3),
                                                  40 + 30 * static_cast<int>(seed), 0.0, false));
  }
  scenes.push_back(std::make_unique<BatchScene>(9, 2, 300, 0.01, true));
  scenes.push_back(std::make_unique<BatchScene>(10, 2, 300, 10.0, true));
  return scenes;
}

TEST(ComputeBatcherTest, StepsInOneBatchAnswerAsEachColliderAlone) {
  const auto scenes = Scenes();
  // Each scene alone, on a collider of this thread's context.
  std::vector<Canonical> alone;
  {
    auto context = GlContext::Create();
    ASSERT_TRUE(context.ok()) << ToString(context.error());
    for (const auto& scene : scenes) {
      auto collider = ComputeCollider::Create();
      ASSERT_TRUE(collider.ok()) << ToString(collider.error());
      auto answer = (*collider)->Run(scene->query);
      ASSERT_TRUE(answer.ok()) << ToString(answer.error());
      alone.push_back(CanonicalOf(*answer));
    }
    ASSERT_GT(std::get<2>(alone.back()).size(), size_t{1} << 16)
        << "the last scene should overflow the first output buffers";
  }
  auto batcher = ComputeBatcher::Create();
  ASSERT_TRUE(batcher.ok()) << ToString(batcher.error());
  std::vector<ComputeBatcher::ColliderId> ids;
  for (size_t i = 0; i < scenes.size(); ++i) {
    auto id = (*batcher)->AddCollider();
    ASSERT_TRUE(id.ok()) << ToString(id.error());
    ids.push_back(*id);
  }
  // Twice: the second round finds the colliders' layouts and grown buffers in place.
  for (int round = 0; round < 2; ++round) {
    (*batcher)->HoldBatches(true);
    std::vector<std::optional<Result<ComputeAnswer>>> batched(scenes.size());
    std::vector<std::thread> threads;
    for (size_t i = 0; i < scenes.size(); ++i) {
      threads.emplace_back(
          [&, i] { batched[i].emplace((*batcher)->Run(ids[i], scenes[i]->query)); });
    }
    for (int wait = 0; wait < 5000 && (*batcher)->queued() < scenes.size(); ++wait)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    EXPECT_EQ((*batcher)->queued(), scenes.size());
    (*batcher)->HoldBatches(false);
    for (std::thread& thread : threads) thread.join();
    for (size_t i = 0; i < scenes.size(); ++i) {
      ASSERT_TRUE(batched[i]->ok()) << ToString(batched[i]->error());
      EXPECT_TRUE(CanonicalOf(**batched[i]) == alone[i]) << "round " << round << " scene " << i;
    }
    const ComputeBatcher::Counters counters = (*batcher)->counters();
    EXPECT_EQ(counters.steps, static_cast<int64_t>((round + 1) * scenes.size()));
    EXPECT_EQ(counters.batches, round + 1) << "all the steps waiting should go in one batch";
    EXPECT_EQ(counters.largest_batch, static_cast<int64_t>(scenes.size()));
  }
}

TEST(ComputeBatcherTest, AnUnknownOrRemovedColliderIsAnError) {
  auto batcher = ComputeBatcher::Create();
  ASSERT_TRUE(batcher.ok()) << ToString(batcher.error());
  BatchScene scene(3, 2, 50, 0.0, false);
  auto unknown = (*batcher)->Run(12345, scene.query);
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().code, ErrorCode::kInternal);
  auto id = (*batcher)->AddCollider();
  ASSERT_TRUE(id.ok()) << ToString(id.error());
  EXPECT_TRUE((*batcher)->Run(*id, scene.query).ok());
  (*batcher)->RemoveCollider(*id);
  EXPECT_FALSE((*batcher)->Run(*id, scene.query).ok());
  EXPECT_FALSE((*batcher)->WithCollider(*id, [](ComputeCollider&) { return Result<void>(); }).ok());
}

TEST(ComputeBatcherTest, ADeviceThatDoesNotExistIsAnErrorFromCreate) {
  auto batcher = ComputeBatcher::Create(GlPlatform::kAuto, 999);
  ASSERT_FALSE(batcher.ok());
  EXPECT_EQ(batcher.error().code, ErrorCode::kUnavailable) << ToString(batcher.error());
}

// Four pipelines, each on its own thread and context as a daemon's sessions are, send their gpu
// steps through one batcher: contacts and distance pairs as the brute-force reference's.
TEST(ComputeBatcherTest, PipelinesOnManyThreadsNeverMissThroughOneBatcher) {
  auto batcher = ComputeBatcher::Create();
  ASSERT_TRUE(batcher.ok()) << ToString(batcher.error());
  constexpr int kThreads = 4;
  constexpr int kScenesPerThread = 12;
  std::vector<std::string> failures(kThreads);
  std::vector<int> contacts(kThreads, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      PipelineOptions options;
      options.num_threads = 1;
      options.compute_batcher = batcher->get();
      auto pipeline = Pipeline::Create(options);
      if (!pipeline) {
        failures[t] = ToString(pipeline.error());
        return;
      }
      ThreadPool pool(1);
      for (int i = 0; i < kScenesPerThread && failures[t].empty(); ++i) {
        const uint64_t seed = 700 + static_cast<uint64_t>(kScenesPerThread * t + i);
        const auto objects = testing::RandomSoup(seed, 4 + static_cast<int>(seed % 4),
                                                 10 + static_cast<int>(seed % 9), 2.0, 0.6);
        for (const auto& object : objects) {
          auto added = (*pipeline)->AddObject(object.id, object.mesh, object.motion, object.X_WO);
          if (!added) failures[t] = ToString(added.error());
        }
        const double D = 0.05 + 0.05 * static_cast<double>(seed % 3);
        const testing::ReferencePairs reference = testing::ReferenceAnswer(objects, D, pool);
        contacts[t] += static_cast<int>(reference.contacts.size());
        StepRequest request;
        request.method = Method::kGpu;
        auto stepped = (*pipeline)->Step(request);
        if (!stepped || stepped->contacts != reference.contacts)
          failures[t] = "seed " + std::to_string(seed) + ": contacts differ";
        request.output = Output::kDistancePairs;
        request.distance = D;
        stepped = (*pipeline)->Step(request);
        if (!stepped || stepped->distance_pairs != reference.distance_pairs)
          failures[t] = "seed " + std::to_string(seed) + ": distance pairs differ";
        for (const auto& object : objects) {
          if (!(*pipeline)->RemoveObject(object.id)) failures[t] = "remove failed";
        }
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  int total = 0;
  for (int t = 0; t < kThreads; ++t) {
    EXPECT_EQ(failures[t], "") << "thread " << t;
    total += contacts[t];
  }
  EXPECT_GT(total, 200) << "the scenes should have contacts to find";
  EXPECT_EQ((*batcher)->counters().steps, 2 * kThreads * kScenesPerThread);
}

}  // namespace
}  // namespace far
