// far-study's CPU path bar on a scene that breaks: besides the median step's FCL / bvh, which
// is a step after the break, the row and the bar name the ratio at every measured step, so that
// the break's own cost is read from the same run.

#include "study_bars.h"

#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace far_study {
namespace {

Row CpuRow(far::Method method, const std::map<int, double>& ms_by_step, double median) {
  Row row;
  row.spec.method = method;
  row.config = row.spec.Name();
  row.method = row.config;
  row.samples = static_cast<int>(ms_by_step.size());
  row.ms_by_step = ms_by_step;
  row.ms_median = median;
  return row;
}

SceneReport Scene(const std::string& name, Kind kind, int break_step) {
  SceneReport report;
  report.name = name;
  report.family = Family::kPaper;
  report.kind = kind;
  report.break_step = break_step;
  report.rows.push_back(CpuRow(far::Method::kFcl, {{1, 0.6}, {2, 100.0}, {3, 4.0}, {4, 4.4}}, 4.2));
  report.rows.push_back(CpuRow(far::Method::kBvh, {{1, 0.3}, {2, 10.0}, {3, 1.0}, {4, 1.1}}, 1.05));
  return report;
}

TEST(StudyBarsTest, BreakingNamesTheRatioAtEveryStep) {
  const Bars bars = EvaluateBars({Scene("breaking", Kind::kBreaking, 2)}, RunOptions{}, RunInfo{});
  const std::string by_step =
      "by step: 2.00x before the break, 10.0x at the break (step 2), 4.00x, 4.00x after it";
  EXPECT_NE(bars.sections.find(by_step), std::string::npos) << bars.sections;
  EXPECT_NE(bars.table.find("breaking 4.00x (" + by_step + ")"), std::string::npos) << bars.table;
  // The bar itself still takes the median step.
  EXPECT_NE(bars.table.find("not met: breaking (4.00x < 10.0x)"), std::string::npos) << bars.table;
}

TEST(StudyBarsTest, OtherScenesHaveNoRatiosByStep) {
  const Bars bars =
      EvaluateBars({Scene("paper-leaves", Kind::kDeformable, 0)}, RunOptions{}, RunInfo{});
  EXPECT_EQ(bars.sections.find("by step"), std::string::npos) << bars.sections;
  EXPECT_EQ(bars.table.find("by step"), std::string::npos) << bars.table;
}

}  // namespace
}  // namespace far_study
