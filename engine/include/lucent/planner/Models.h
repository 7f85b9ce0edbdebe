// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The Auto planner's cost and error models: per candidate (a method's evaluation
/// variant at one quality level), a prediction of its frame time as a ratio to the Direct
/// render of the same frame and of its 4×4-block relative L1 error against the exact
/// reference, each a function of the scene's features. Fitted on the evaluation suite's
/// measurements (`lucent-cli plan --fit suite.csv -o resources/planner/models.json`), stored as
/// data, shipped embedded in the binary (defaultModels()).
///
///     const Models& m = defaultModels();
///     std::vector<Candidate> c = toCandidates(m);     // for plan() (Planner.h)
///     double e = predictError(m.candidates[0], analyzeScene(scene));
///
/// Both models are log-linear: log(y) = Σ_k c_k·t_k(features), with the terms below chosen so
/// that each is of order one over the scenes the tool is for. Log-linear because both
/// quantities are positive and vary by factors (a method twice as wrong on a back-lit scene),
/// not by offsets. The fit is ridge-regularised least squares (the intercept not penalised):
/// the suite has a few dozen cases per candidate, fewer than would pin ten free coefficients.

#include <lucent/planner/Planner.h>
#include <lucent/planner/SceneFeatures.h>

#include <string>
#include <vector>

namespace lucent::planner {

/// One measured row of an evaluation: a candidate on one case.
struct MeasuredRow {
    std::string caseName;     ///< suite case ("marble_sphere_eta1.3")
    std::string method;       ///< registry name with the evaluation variant: "sslpv:paper"
    std::string setting;      ///< quality level name: "16 spp"
    double costRatio = 0.0;   ///< frame time / the Direct render of the same frame
    double blockRelL1 = 0.0;  ///< 4×4-block relative L1 against the exact reference
    /// The reference's own noise in the same metric (0 when unknown): errors closer than this
    /// are equal as far as the measurement can tell.
    double noiseFloor = 0.0;
    /// Block relative L1 of this setting's image against the same method's next finer
    /// setting on the case (< 0: not measured): the level check's input (LevelCheck.h).
    double blockRelL1ToFiner = -1.0;
    /// The Direct render's time the cost ratio was taken against (ms; 0 when the CSV has no
    /// such column): rows of one case measured in different runs have different units.
    double directUnitMs = 0.0;
    SceneFeatures features;
};

/// A candidate's fitted models.
struct CandidateModel {
    std::string method;         ///< "sslpv:paper" (registry name[:variant])
    std::string setting;        ///< quality level name, as the registry names it
    std::vector<double> cost;   ///< coefficients over costTerms()
    std::vector<double> error;  ///< coefficients over errorTerms()
    int cases = 0;              ///< measured cases the fit used
    /// Leave-one-case-out RMS of log(prediction / measurement): how far to trust the model
    /// (0.1 ≈ ±10 %).
    double costLogRms = 0.0;
    double errorLogRms = 0.0;
};

/// Every candidate's models.
struct Models {
    static constexpr int VERSION = 1;  ///< bumped when the terms change (old files are refused)
    std::string source;                ///< what they were fitted on: the command and the suite
    double ridge = 0.0;                ///< the regularisation used
    std::vector<CandidateModel> candidates;
};

//! @{ \name Terms (names and values, same order)
const std::vector<std::string>& costTermNames();
std::vector<double> costTerms(const SceneFeatures& f);
const std::vector<std::string>& errorTermNames();
std::vector<double> errorTerms(const SceneFeatures& f);
//! @}

/// Predicted frame time / Direct frame time (> 0).
double predictCost(const CandidateModel& model, const SceneFeatures& f);
/// Predicted 4×4-block relative L1 (> 0).
double predictError(const CandidateModel& model, const SceneFeatures& f);

/// Fits one model per (method, setting) present in `rows`, skipping rows without a positive,
/// finite cost and error. A candidate measured on fewer than 2 cases is left out (nothing to
/// fit a scene dependence on). @throw ValueError if no candidate can be fitted.
Models fitModels(const std::vector<MeasuredRow>& rows, double ridge = 0.05);

/// `rows` without the `direct` and `reference` rows: the unlit baseline and the measuring stick
/// are not previews to choose from, so no model is fitted for them.
std::vector<MeasuredRow> previewRows(std::vector<MeasuredRow> rows);

/// Reads an evaluation CSV (`lucent-cli evaluate --suite` writes one): a header row naming
/// the columns, then one row per case, method and setting. Columns are found by name:
/// case (or scene), method, setting, cost_ratio (or time_ms with direct_ms), block_rel_l1,
/// one column per SceneFeatures field (camelCase, snake_case or feature_snake_case); optional:
/// lights, noise_floor (or block_rel_l1_floor), block_rel_l1_to_finer (empty cells: not
/// measured). Rows of the `direct` and
/// `reference` methods are read like any other (the caller decides what to fit).
/// @throw IoError naming the file; ValueError naming the missing column or the bad line.
/// Which cost to read: the wall-time ratio (cost_ratio, or time_ms / direct_ms) or the process
/// CPU-time ratio (cpu_cost_ratio, or cpu_ms / direct_cpu_ms). On a shared machine the wall
/// time of the same render varies many-fold with the other load while its CPU time does not.
enum class CostMeasure { WallTime, CpuTime };
std::vector<MeasuredRow> readMeasurements(const std::string& csvPath,
                                          CostMeasure cost = CostMeasure::WallTime);

/// Rows whose cost ratios are not comparable with the rest of their case: a method whose rows
/// were timed against a Direct unit more than `limit` times off the case's median unit (rows
/// merged from runs on a differently loaded machine; load inflates llvmpipe's CPU time, so even
/// CPU-time ratios move). One line per case and method, naming both units; empty when every
/// row's unit is within the limit or unknown.
std::vector<std::string> costUnitWarnings(const std::vector<MeasuredRow>& rows, double limit = 1.5);

/// JSON (docs/planner.md, "Models file"). @throw IoError / ValueError naming the file, for an
/// unreadable file, malformed JSON, another VERSION or a coefficient count that does not match
/// the terms.
Models loadModels(const std::string& path);
Models parseModels(const std::string& json, const std::string& origin);
std::string formatModels(const Models& models);
/// Writes atomically. @throw IoError naming the file.
void saveModels(const Models& models, const std::string& path);

/// The models shipped with this build (resources/planner/models.json, embedded).
const Models& defaultModels();

/// Auto's choice on one measured case against the measured run-time-vs-error front (issue 15's
/// check: within 1.2× the time of the best point at equal error).
struct FrontCheck {
    std::string caseName;
    std::string chosen;  ///< "method setting" Auto picked from the models' predictions
    /// The models' pick before the level check stepped down ("" when it kept the level).
    std::string planned;
    double chosenCost = 0.0, chosenError = 0.0;  ///< its measured cost ratio and block error
    /// The cheapest measured candidate at or under the chosen one's measured error plus the
    /// reference noise floor (errors closer than the floor are equal).
    std::string cheapestAtError;
    double cheapestCost = 0.0;
    /// chosenCost / cheapestCost (≥ 1; 1 when Auto's choice is on the front).
    double timeRatio = 1.0;
    /// The measured best under the budget: least error among candidates within it (the
    /// cheapest when none is).
    std::string bestInBudget;
    double bestError = 0.0;
    /// Auto's choice is bestInBudget, or within the reference noise floor of its error (and on
    /// the same side of the budget).
    bool choseBest = false;
};

/// For every case in `rows`, plans with `models` on the case's features (only candidates that
/// were measured on that case take part) under a budget of `budgetRatio` × the Direct frame,
/// replays the level check (LevelCheck.h) on the rows' blockRelL1ToFiner unless
/// `levelTolerance` is off, then judges the choice by the measured rows. Rows of candidates
/// without a model are left out. `errorTolerance`: the planner's Budget::errorTolerance.
/// `measuredErrors`: plan with each case's measured errors in place of the predicted ones (the
/// costs stay predicted), as Auto does when it measures the scene on its own
/// (chooseByMeasuring, MeasureScene.h); the level check is then not replayed. Those errors are
/// `rows`' own unless `plannedErrors` gives other rows of the same cases and candidates (the
/// suite scored against an independent reference, `evaluate --ref-seed`): Auto's measurement
/// has its own reference, so planning and judging by one reference's errors flatters it.
/// @throw ValueError if budgetRatio ≤ 0, the error tolerance is outside [0, 1), a level
/// tolerance is negative, or `plannedErrors` lacks a candidate measured in `rows`.
std::vector<FrontCheck> checkAgainstFront(const std::vector<MeasuredRow>& rows,
                                          const Models& models, double budgetRatio,
                                          double errorTolerance = Budget{}.errorTolerance,
                                          LevelTolerance levelTolerance = {0.0, 0.0},
                                          bool measuredErrors = false,
                                          const std::vector<MeasuredRow>* plannedErrors = nullptr);

/// checkAgainstFront with each case judged by models that have not seen it: for every case,
/// fitModels(previewRows(the other cases' rows), ridge), then that case's check. The in-sample
/// check (models fitted on the rows they are judged on) flatters them; this is how Auto fares
/// on a scene outside its fit. Cases whose remaining rows fit no candidate are left out.
/// @throw ValueError as checkAgainstFront, or if fewer than 2 cases are given.
std::vector<FrontCheck> crossValidatedCheck(
    const std::vector<MeasuredRow>& rows, double ridge, double budgetRatio,
    double errorTolerance = Budget{}.errorTolerance, LevelTolerance levelTolerance = {0.0, 0.0},
    bool measuredErrors = false, const std::vector<MeasuredRow>* plannedErrors = nullptr);

/// `rows` with each row's error (blockRelL1) and noise floor taken from the row of `errors`
/// with the same case, method and setting: the same renders scored against another reference
/// (`evaluate --ref-floor` for a sharper one, `--ref-seed` for an independent one). Costs,
/// features and the level differences (image against image) stay `rows`'.
/// @throw ValueError if `errors` has no finite error for one of `rows`' candidates.
std::vector<MeasuredRow> withErrorsOf(std::vector<MeasuredRow> rows,
                                      const std::vector<MeasuredRow>& errors);

/// The planner's candidates for `models` (costRatio and error bound to the models; `unusable`
/// left empty: the caller knows what the scene and backend allow).
std::vector<Candidate> toCandidates(const Models& models);

}  // namespace lucent::planner
