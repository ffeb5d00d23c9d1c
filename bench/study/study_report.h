#pragma once

// far-study's outputs: the CSV, the per-scene and scaling tables, the plots and the study section
// of bench/RESULTS.md. The bars are in study_bars.h.

#include <string>
#include <vector>

#include "study_run.h"

namespace far_study {

/// Where and how the run was made: stated above every table section.
struct RunInfo {
  std::string command;  ///< the exact argv, program name as "far-study"
  std::string renderer, cpu, date;
  int cpus = 0;
  double seconds = 0;  ///< the whole run
};

/// "Command: `...`. Machine: ... Date ... Whole run: ...", one paragraph.
std::string RunLine(const RunInfo& info);

// Number formatting of the tables.
std::string Fixed(double value, int digits);
std::string Ms(double ms);  ///< about three significant digits
std::string Count(double value);
std::string Ratio(double value);
/// "missed / spurious" of contacts, or "not checked" without a reference; "(3 of 6 steps
/// checked)" after it where the reference ran on some of the row's steps only.
std::string Misses(const Row& row);
/// Steps of the row checked against the reference: "all 6", "3 of 6", "none".
std::string CheckedSteps(const Row& row);
/// The same as Misses for distance pairs ("-" for a row without the distance pass).
std::string DistanceMisses(const Row& row);
/// "ingest 0.01, update 0.03, ..." (stages of 5 us or more).
std::string StageText(const Row& row);
/// What a row ran, by measured steps: "bvh x3, aabb x1".
std::string RunsText(const Row& row);

/// False when the file cannot be written.
bool WriteCsv(const std::string& path, const std::vector<SceneReport>& reports);
std::string SceneTable(const SceneReport& report);
/// Triangles x configurations, median ms per step, over the scaling scenes ("" without any).
std::string ScalingTable(const std::vector<SceneReport>& reports);

/// Runs `script` through gnuplot on `csv` into `png`; false when gnuplot fails.
bool Plot(const std::string& script, const std::string& csv, const std::string& png);

/// Replaces the text between the study markers in `path` (appends it when the markers are not
/// there; creates the file with a header when it does not exist). Other sections are kept.
bool WriteResultsSection(const std::string& path, const std::string& section);

}  // namespace far_study
