#pragma once

// far-study's bars: each target, evaluated on the rows of one run and printed with its measured
// ratio and "met" or "not met" (or "not evaluated" when the run lacks what it needs).
//  - the issue "Fast on every host": auto within 1.2x of the fastest reliable configuration on
//    every scene; the CPU path (bvh) against FCL with 0 missed and 0 spurious contacts and
//    distance pairs on the paper-scale and scaling scenes; the GL path (FAR's fastest reliable
//    configuration) within 5x of FCL on paper-leaves;
//  - the paper's, on the small scenes: ID buffer against occlusion queries, FAR against CULLIDE,
//    candidate pairs against AABB sweep-and-prune.

#include <string>
#include <vector>

#include "study_report.h"
#include "study_run.h"

namespace far_study {

struct Bars {
  std::string table;     ///< Markdown: one row per bar (measured, target, met)
  std::string sections;  ///< Markdown: the tables behind the bars, each with the run line
  std::string summary;   ///< one line per bar, for stdout
};

Bars EvaluateBars(const std::vector<SceneReport>& reports, const RunOptions& options,
                  const RunInfo& info);

}  // namespace far_study
