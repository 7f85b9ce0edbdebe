// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief What an evaluation writes: results.csv (one row per case × method × setting, with the
/// case's scene features, for fitting the planner's cost and error models), results.json,
/// summary.md (per case the best method and whether it meets the goal), pareto.md (the
/// Pareto front of cost vs error per case) and the gnuplot data + script that draw run time vs
/// error per case and one summary chart (charts are a docs step: `gnuplot DIR/charts.gp`).
///
///     RunInfo info;  info.suite = "default";  ...
///     writeReports(results, info, "build/evaluation");

#include <lucent/evaluation/Evaluate.h>

#include <string>
#include <vector>

namespace lucent::evaluation {

/// The run's settings, recorded beside the results.
struct RunInfo {
    std::string suite;    ///< "default", "smoke" or "files"
    std::string command;  ///< the command line that reproduces the run
    int width = 0, height = 0, refSpp = 0, repeats = 0;
    int refSeed = 1;        ///< the reference's seed (RunOptions::refSeed)
    double refFloor = 0.0;  ///< RunOptions::refFloor (0: every reference at refSpp)
    int refMaxSpp = 0;      ///< RunOptions::refMaxSpp, with refFloor
    bool subsurfaceOnly = false;
    std::vector<std::string> cases;
    std::vector<double> referenceSeconds;  ///< per case (0 when cached)
    std::vector<double> noiseFloors;       ///< per case: the reference's block rel. L1 floor
    std::vector<int> referenceSpp;         ///< per case: the reference's samples per pixel
    std::vector<std::string> skipped;
};

/// results.csv: header and one row per result. Columns: case, group, method, setting,
/// quality, backend, time_ms, time_min_ms, runs, direct_ms, cost_ratio, cpu_ms, direct_cpu_ms,
/// cpu_cost_ratio, block_rel_l1,
/// block_rel_l1_raw, block_rel_rmse, block_rel_rmse_raw, mean_ratio, p95, noise_floor,
/// noise_floor_rmse, pixel_rel_rmse, pixel_rel_rmse_floor, block_rel_l1_{r,g,b},
/// block_rel_rmse_{r,g,b}, mean_ratio_{r,g,b}, pixels, meets_goal, then one feature_<name>
/// column per planner::SceneFeatures field (empty when the case could not be analysed).
std::string toCsv(const std::vector<Result>& results);
/// The CSV header alone (tests, readers).
std::string csvHeader();
/// results.json: the run info and the results with the same fields as the CSV.
std::string toJson(const std::vector<Result>& results, const RunInfo& info);
/// Per case: the best result (lowest block rel. L1, then lowest CPU cost), its errors, the
/// noise floor, the wall and CPU cost ratios and whether it meets the goal, and the result of
/// lowest CPU cost within the goal (if any), as a Markdown table.
std::string summaryMarkdown(const std::vector<Result>& results);
/// Per case: the Pareto front of (CPU cost ratio, block rel. L1), cheapest first, as Markdown.
/// CPU rather than wall time: other processes on a shared box move a case's wall-time ratios
/// by up to 3x (docs/evaluation.md), its CPU-time ratios far less.
std::string paretoMarkdown(const std::vector<Result>& results);
/// The gnuplot script that reads DIR/chart_<case>.dat and DIR/chart_summary.dat (written by
/// writeReports) and writes runtime_vs_error_<case>.png and runtime_vs_error.png.
std::string gnuplotScript(const std::vector<Result>& results, const RunInfo& info);

/// Writes results.csv, results.json, summary.md, pareto.md, chart_*.dat and charts.gp into
/// `dir` (atomically, file by file). @return the paths written. @throw IoError.
std::vector<std::string> writeReports(const std::vector<Result>& results, const RunInfo& info,
                                      const std::string& dir);
/// Writes what is derived from the results: summary.md, pareto.md, chart_*.dat, charts.gp.
std::vector<std::string> writeDerivedReports(const std::vector<Result>& results,
                                             const RunInfo& info, const std::string& dir);

/// Reads results.csv back (every column toCsv writes; the metrics it does not hold stay 0), so
/// that the derived reports can be redrawn without rendering again (`evaluate --report DIR`).
/// @param origin the file name for messages. @throw IoError naming the line and column.
std::vector<Result> parseResultsCsv(const std::string& text, const std::string& origin);
/// Reads the run info of results.json. @throw IoError when it is not one.
RunInfo parseRunInfoJson(const std::string& text, const std::string& origin);

}  // namespace lucent::evaluation
