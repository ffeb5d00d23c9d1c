// PipelineOptions::cpu_cores: the cores a pipeline may use bound its CPU pool, with num_threads
// or alone; a pipeline on one core still steps.
#include <algorithm>
#include <thread>

#include <gtest/gtest.h>

#include "far/pipeline/pipeline.h"
#include "far/scenes/scenes.h"

namespace far {
namespace {

std::unique_ptr<Pipeline> CpuPipeline(int num_threads, int cpu_cores) {
  PipelineOptions options;
  options.use_gl = false;
  options.num_threads = num_threads;
  options.cpu_cores = cpu_cores;
  auto pipeline = Pipeline::Create(options);
  EXPECT_TRUE(pipeline.ok()) << ToString(pipeline.error());
  return pipeline.ok() ? std::move(*pipeline) : nullptr;
}

TEST(PipelineCpuCoresTest, APipelineOnOneCoreRunsItsPoolOnOneThreadAndSteps) {
  auto pipeline = CpuPipeline(/*num_threads=*/0, /*cpu_cores=*/1);
  ASSERT_NE(pipeline, nullptr);
  EXPECT_EQ(pipeline->cpu_threads(), 1);
  for (const SceneObject& o : scenes::RandomSoup(7, 12, 40, 2.0, 0.4)) {
    ASSERT_TRUE(pipeline->AddObject(o.id, o.mesh, o.motion, o.X_WO).ok());
  }
  StepRequest request;
  request.method = Method::kBvh;
  auto result = pipeline->Step(request);
  EXPECT_TRUE(result.ok()) << ToString(result.error());
}

TEST(PipelineCpuCoresTest, ThePoolTakesTheSmallerOfThreadsAndCoresWhereEachIsGiven) {
  EXPECT_EQ(CpuPipeline(4, 2)->cpu_threads(), 2);
  EXPECT_EQ(CpuPipeline(2, 4)->cpu_threads(), 2);
  EXPECT_EQ(CpuPipeline(3, 0)->cpu_threads(), 3);
  EXPECT_EQ(CpuPipeline(0, 3)->cpu_threads(), 3);
  const int machine = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  EXPECT_EQ(CpuPipeline(0, 0)->cpu_threads(), machine);
  EXPECT_EQ(CpuPoolThreads(0, 0), machine);
  EXPECT_EQ(CpuPoolThreads(8, 1), 1);
}

}  // namespace
}  // namespace far
