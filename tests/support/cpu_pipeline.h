#pragma once

#include <memory>

#include <gtest/gtest.h>

#include "far/pipeline/pipeline.h"

namespace far::testing {

/// A pipeline with the CPU methods only (no GL context) and two threads; null (and a test
/// failure) when it cannot be made.
inline std::unique_ptr<Pipeline> CpuPipeline() {
  PipelineOptions options;
  options.use_gl = false;
  options.num_threads = 2;
  auto pipeline = Pipeline::Create(options);
  EXPECT_TRUE(pipeline.ok());
  return pipeline.ok() ? std::move(*pipeline) : nullptr;
}

}  // namespace far::testing
