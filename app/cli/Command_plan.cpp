// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli plan SCENE.json`: what the Auto planner sees in a scene and what it
/// chooses (lucent/planner/AutoMethod.h); `lucent-cli plan --fit suite.csv -o models.json`:
/// fits the planner's cost and error models (lucent/planner/Models.h). Parsing and printing
/// only.

#include "CliCommon.h"

#include <lucent/core/Error.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/planner/AutoMethod.h>
#include <lucent/planner/LevelCheck.h>
#include <lucent/scene/SceneFile.h>

#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace lucent::cli {

namespace {

/// "50 ms", "0.1": numbers as a user typed them.
std::string fmtMs(double v, bool ms = true) {
    char buf[64];
    std::snprintf(buf, sizeof buf, ms ? "%g ms" : "%g", v);
    return buf;
}

void printFeatures(const planner::SceneFeatures& f) {
    std::printf("scene features (object 0):\n");
    std::printf("  size %.3g mm, %.3g mean free paths (mean sigma_t' %.4g /mm), albedo' %.4f\n",
                f.sizeMm, f.opticalSize, f.meanSigmaT, f.albedo);
    std::printf(
        "  diffusion length %.3g mm, deepest voxel %.3g mm, thin fraction %.2f, "
        "curvature %.3g\n",
        f.diffusionLengthMm, f.maxDepthMm, f.thinFraction, f.curvature);
    std::printf("  sigma_t' variation %.3f, albedo' spread %.3f, mean |g| %.2f, eta %.3g\n",
                f.sigmaTVariation, f.albedoVariation, f.meanAbsG, f.eta);
    std::printf("  %d light(s), back-lit fraction %.2f, %.0f of %.0f pixels covered\n", f.lights,
                f.backLitFraction, f.pixelsCovered, f.imagePixels);
}

/// --measure: the frame measured, the reference, and each candidate's measured error beside
/// its prediction.
void printMeasurement(const planner::OwnReferenceMeasurement& m, const planner::Models& models,
                      const planner::AutoChoice& c) {
    std::printf(
        "\nmeasured on a %dx%d frame against the exact reference (%d spp, %.1f s; its "
        "noise floor %.3f):\n",
        m.width, m.height, m.referenceSpp, m.referenceSeconds, m.referenceNoise);
    std::printf("%-22s %-20s %14s %12s\n", "candidate", "setting", "measured error", "render ms");
    for (const planner::CandidateMeasurement& cm : m.measurement.candidates) {
        if (!cm.ok()) {
            std::printf("%-22s %-20s %14s  %s\n", cm.method.c_str(), cm.setting.c_str(), "failed",
                        cm.failed.c_str());
            continue;
        }
        const planner::CandidateModel& chosen = models.candidates[c.plan.choice];
        const bool isChosen = chosen.method == cm.method && chosen.setting == cm.setting;
        std::printf("%-22s %-20s %14.3f %12.1f%s\n", cm.method.c_str(), cm.setting.c_str(),
                    cm.blockRelL1, cm.ms, isChosen ? "  <- chosen" : "");
    }
    if (m.measurement.cancelled)
        std::printf("(stopped before every candidate was measured)\n");
}

struct PlanOptions {
    std::string scene, models, output, source, cost = "wall";
    std::vector<std::string> fit, check, plannedErrors, judgedErrors;
    float budgetMs = 1000.f, maxError = 0.f, directMs = 1.f, ridge = 0.05f, budgetRatio = 20.f,
          errorTolerance = float(planner::Budget{}.errorTolerance);
    planner::LevelTolerance levelTolerance;
    planner::OwnReferenceOptions measureOptions;
    int width = 0, height = 0;
    bool cpu = false, measure = false, crossValidate = false;
    const CLI::App* app = nullptr;
    bool has(const std::string& option) const { return app->count(option) > 0; }
    planner::CostMeasure costMeasure() const {
        return cost == "cpu" ? planner::CostMeasure::CpuTime : planner::CostMeasure::WallTime;
    }
    planner::Models loadModels() const {
        return has("--models") ? planner::loadModels(models) : planner::defaultModels();
    }
};

/// Cost ratios of one case taken against Direct units far apart (rows from differently loaded
/// runs) would be fitted or judged as if comparable: say so before using them.
void warnAboutCostUnits(const std::vector<planner::MeasuredRow>& rows) {
    for (const std::string& w : planner::costUnitWarnings(rows))
        std::fprintf(stderr, "warning: %s\n", w.c_str());
}

/// The rows of every CSV in `paths`, in order.
std::vector<planner::MeasuredRow> readAll(const std::vector<std::string>& paths,
                                          planner::CostMeasure cost) {
    std::vector<planner::MeasuredRow> rows;
    for (const std::string& csv : paths) {
        std::vector<planner::MeasuredRow> r = planner::readMeasurements(csv, cost);
        rows.insert(rows.end(), r.begin(), r.end());
    }
    return rows;
}

void runFit(const PlanOptions& args) {
    const std::string& out = args.output;
    if (out.empty())
        LUCENT_THROW(ValueError, "plan --fit: missing -o/--output models.json");
    const double ridge = args.ridge;
    std::vector<planner::MeasuredRow> rows = readAll(args.fit, args.costMeasure());
    std::string source = "lucent-cli plan --cost " + args.cost + " --fit";
    for (const std::string& csv : args.fit)
        source += " " + csv;
    warnAboutCostUnits(rows);
    rows = planner::previewRows(std::move(rows));
    planner::Models models = planner::fitModels(rows, ridge);
    models.source = args.has("--source") ? args.source : source;
    planner::saveModels(models, out);
    std::printf("%-22s %-20s %5s %14s %15s\n", "method", "setting", "cases", "cost log-RMS",
                "error log-RMS");
    for (const planner::CandidateModel& c : models.candidates)
        std::printf("%-22s %-20s %5d %14.3f %15.3f\n", c.method.c_str(), c.setting.c_str(), c.cases,
                    c.costLogRms, c.errorLogRms);
    std::printf("wrote %s (%zu candidates from %zu rows; log-RMS: leave-one-out, ln units)\n",
                out.c_str(), models.candidates.size(), rows.size());
}

void runCheck(const PlanOptions& args) {
    if (!args.plannedErrors.empty() && !args.measure)
        LUCENT_THROW(ValueError,
                     "--planned-errors is what Auto plans with under --measure: give "
                     "--measure too");
    const bool crossValidate = args.crossValidate;
    if (crossValidate && args.has("--models"))
        LUCENT_THROW(ValueError,
                     "plan --check --cross-validate fits its own models (one per case left out): "
                     "give --models or --cross-validate, not both");
    const planner::Models models = crossValidate ? planner::Models{} : args.loadModels();
    const double budgetRatio = args.budgetRatio;
    std::vector<planner::MeasuredRow> rows = readAll(args.check, args.costMeasure());
    warnAboutCostUnits(rows);
    // --judged-errors: the same renders scored against another (e.g. a sharper) reference;
    // with --cross-validate the left-out fits are made on those errors too.
    if (!args.judgedErrors.empty())
        rows =
            planner::withErrorsOf(std::move(rows), readAll(args.judgedErrors, args.costMeasure()));
    // --planned-errors: the same candidates' errors against another reference.
    const std::vector<planner::MeasuredRow> planning =
        readAll(args.plannedErrors, args.costMeasure());
    const std::vector<planner::MeasuredRow>* planned = planning.empty() ? nullptr : &planning;
    const std::vector<planner::FrontCheck> checks =
        crossValidate
            ? planner::crossValidatedCheck(rows, args.ridge, budgetRatio, args.errorTolerance,
                                           args.levelTolerance, args.measure, planned)
            : planner::checkAgainstFront(rows, models, budgetRatio, args.errorTolerance,
                                         args.levelTolerance, args.measure, planned);
    if (checks.empty())
        LUCENT_THROW(ValueError, "plan --check: no case has a measured candidate with a model");
    const std::string fitNote = crossValidate ? "each case planned by models fitted on the other "
                                                "cases (ridge " +
                                                    std::to_string(args.ridge).substr(0, 5) + "); "
                                              : "";
    std::printf(
        "budget: %g x the Direct frame; times are measured cost ratios, errors measured\n"
        "block rel. L1%s; %s%s\n\n",
        budgetRatio,
        args.judgedErrors.empty() ? "" : " against --judged-errors' reference (its floors)",
        fitNote.c_str(),
        args.measure && planned
            ? "Auto plans with the errors of --planned-errors, measured against another "
              "reference, and is judged by --check's (--measure: no level check)"
        : args.measure ? "Auto plans with the measured errors (--measure: no level check)"
        : args.levelTolerance.off()
            ? "level check off"
            : ("level check max(" + std::to_string(args.levelTolerance.absolute).substr(0, 5) +
               ", " + std::to_string(args.levelTolerance.relative).substr(0, 4) +
               " x the predicted error); \"<\" marks a choice it moved to a cheaper level")
                  .c_str());
    std::printf("%-28s %-36s %8s %7s  %-36s %6s  %s\n", "case", "Auto's choice", "cost", "error",
                "cheapest at that error", "ratio", "best in budget");
    int within = 0, best = 0;
    for (const planner::FrontCheck& c : checks) {
        within += c.timeRatio <= 1.2 ? 1 : 0;
        best += c.choseBest ? 1 : 0;
        std::printf("%-28s %-36s %8.2f %7.3f  %-36s %6.2f  %s%s\n", c.caseName.c_str(),
                    (c.chosen + (c.planned.empty() ? "" : " <")).c_str(), c.chosenCost,
                    c.chosenError, c.cheapestAtError.c_str(), c.timeRatio,
                    c.choseBest ? "= chosen" : c.bestInBudget.c_str(),
                    c.choseBest
                        ? ""
                        : (" (error " + std::to_string(c.bestError).substr(0, 5) + ")").c_str());
    }
    std::printf(
        "\nwithin 1.2x of the front at equal error: %d of %zu cases; the best point in the "
        "budget: %d of %zu\n",
        within, checks.size(), best, checks.size());
}

void runPlan(const PlanOptions& args) {
    if (args.has("--ridge") && args.fit.empty() && !args.crossValidate)
        LUCENT_THROW(ValueError, "--ridge applies to --fit and --check --cross-validate");
    if (!args.fit.empty())
        return runFit(args);
    if (!args.check.empty())
        return runCheck(args);
    if (args.scene.empty())
        LUCENT_THROW(ValueError, "expected one SCENE.json, --fit CSV or --check CSV (see --help)");
    Scene scene = loadScene(args.scene);
    for (const std::string& w : scene.warnings)
        std::fprintf(stderr, "lucent-cli plan: warning: %s\n", w.c_str());
    overrideImageSize(*args.app, args.width, args.height, scene.camera.width, scene.camera.height);
    const planner::Models models = args.loadModels();
    std::string glReason;
    const bool gl = !args.cpu && gpu::GlContext::isHeadlessAvailable(&glReason);
    if (args.measure && !gl)  // the Direct frame, the costs' unit, renders with GL only
        LUCENT_THROW(ValueError,
                     "plan --measure renders the candidates and the Direct frame with OpenGL, "
                     "which is not available (",
                     args.cpu ? "--cpu" : glReason, ")");
    planner::Budget budget;
    budget.frameMs = args.budgetMs;
    budget.maxError = args.maxError;
    budget.directMs = args.has("--direct-ms") ? double(args.directMs) : 0.0;
    const methods::Log log = [](const std::string& m) {
        std::fprintf(stderr, "plan: %s\n", m.c_str());
    };
    planner::AutoChoice c = planner::chooseOffline(scene, models, budget, gl, log);
    const size_t planned = c.plan.choice;
    std::optional<planner::OwnReferenceMeasurement> measured;
    if (args.measure) {
        // Measured errors tell the levels apart: no level check after them.
        planner::OwnReferenceOptions mo = args.measureOptions;
        mo.render.log = log;
        planner::MeasuredChoice m =
            planner::chooseByMeasuring(scene, models, c, budget, gl, mo, log);
        c = std::move(m.choice);
        measured = std::move(m.measurement);
    } else if (!args.levelTolerance.off()) {
        planner::LevelCheckOptions lo;
        lo.tolerance = args.levelTolerance;
        lo.render.log = log;
        planner::runLevelCheck(scene, models, c, lo);
    }
    printFeatures(c.features);
    std::printf("scene class: %s\n", planner::describe(c.plan.sceneClass, c.features.eta).c_str());
    std::printf("Direct frame: %s; %s\n",
                args.has("--direct-ms") ? fmtMs(c.directMs).c_str()
                : gl                    ? (fmtMs(c.directMs) + " (measured)").c_str()
                                        : "none (no GL)",
                budget.maxError > 0 ? ("error target " + fmtMs(budget.maxError, false)).c_str()
                                    : ("budget " + fmtMs(budget.frameMs)).c_str());
    if (!gl)
        std::printf("no GL: %s\n", args.cpu ? "--cpu" : glReason.c_str());
    std::printf("\n%-22s %-20s %12s %12s %5s\n", "candidate", "setting", "predicted ms",
                "block error", "fits");
    for (const planner::Option& o : c.plan.options) {
        const planner::CandidateModel& m = models.candidates[o.index];
        std::printf("%-22s %-20s %12.1f %12.3f %5s%s\n", m.method.c_str(), m.setting.c_str(), o.ms,
                    o.error, o.fits ? "yes" : "no",
                    o.index == c.plan.choice ? "  <- chosen"
                    : o.index != planned     ? ""
                    : measured               ? "  <- the models' pick"
                                             : "  <- planned (level check: see the plan)");
    }
    if (measured)
        printMeasurement(*measured, models, c);
    std::printf("\nplan: %s\n", c.plan.reason.c_str());
    std::printf("render: lucent-cli render %s --method %s%s", args.scene.c_str(), c.method.c_str(),
                c.backend == methods::Backend::Auto
                    ? ""
                    : (std::string(" --backend ") + methods::backendName(c.backend)).c_str());
    for (const auto& [k, v] : c.params.items())
        std::printf(" --param %s=%s", k.c_str(), v.c_str());
    std::printf("\n");
}

}  // namespace

void addPlanCommand(CLI::App& cli, const CommandContext&) {
    CLI::App* sub = addCommand(
        cli, "plan",
        "what the Auto planner sees in a scene and which method it picks; fits its models",
        "usage: lucent-cli plan SCENE.json [--budget-ms B | --max-error E] [--direct-ms D]\n"
        "                       [--models models.json] [--width W] [--height H] [--cpu]\n"
        "       lucent-cli plan --fit suite.csv [--fit more.csv ...] -o models.json [--ridge R]\n"
        "       lucent-cli plan --check suite.csv [--models F | --cross-validate [--ridge R]]\n"
        "                       [--budget-ratio R]\n"
        "  SCENE and --check: [--level-tolerance T] [--level-relative K] [--no-level-check]\n"
        "  SCENE: [--measure [--measure-width W] [--measure-spp N]];\n"
        "  --check: [--measure [--planned-errors CSV]] [--judged-errors CSV]\n",
        "Prints the scene's features and class, every candidate (a method at one quality level)\n"
        "with its predicted time and 4x4-block error against the exact reference, the choice and\n"
        "its one-line reason, and the `lucent-cli render` command that renders it\n"
        "(`render --method auto` does both). The level check then renders the chosen level and\n"
        "the method's cheaper ones on a 64-pixel-wide frame and takes the cheapest whose image\n"
        "differs from the chosen one by at most max(T, K x its predicted error) (block rel. L1).\n"
        "With --measure it instead renders the exact reference of the frame at W pixels across\n"
        "and every candidate within the budget against it, and plans with the measured errors.\n"
        "docs/planner.md explains the models, the check and the measurement.\n");
    auto args = std::make_shared<PlanOptions>();
    args->app = sub;
    CLI::Option* scene =
        sub->add_option("SCENE.json", args->scene, "the scene to plan")->check(existingFile());
    sub->add_option("--budget-ms", args->budgetMs,
                    "time the render may take (default 1000 ms; predicted as the model's cost "
                    "ratio times the Direct render of the same frame)")
        ->type_name("B")
        ->check(finiteRange(1e-3, 1e9));
    sub->add_option("--max-error", args->maxError,
                    "instead: the cheapest candidate predicted at or under block error E")
        ->type_name("E")
        ->check(finiteRange(0, 1e3));
    sub->add_option("--direct-ms", args->directMs,
                    "this machine's Direct render of the frame (default: measured now)")
        ->type_name("D")
        ->check(finiteRange(1e-3, 1e9));
    sub->add_option("--models", args->models,
                    "models file (default: the ones built in, resources/planner/models.json)")
        ->type_name("F")
        ->check(existingFile());
    addImageSizeOptions(*sub, args->width, args->height);
    sub->add_flag("--cpu", args->cpu, "plan as if no OpenGL were available");
    CLI::Option* fit =
        sub->add_option("--fit", args->fit,
                        "fit the models on an evaluation CSV (`lucent-cli evaluate --suite`), one "
                        "model per method and setting measured on at least 2 cases (repeatable)")
            ->type_name("CSV")
            ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
            ->check(existingFile())
            ->excludes(scene);
    sub->add_option("-o,--output", args->output, "--fit: the models file to write")
        ->type_name("models.json")
        ->needs(fit);
    sub->add_option("--ridge", args->ridge,
                    "regularisation of the fit (--fit, --check --cross-validate; default 0.05)")
        ->type_name("R")
        ->check(finiteRange(0, 100));
    sub->add_option("--source", args->source, "--fit: the models' source note")
        ->type_name("TEXT")
        ->needs(fit);
    sub->add_option("--cost", args->cost,
                    "--fit/--check: the cost column, wall-time or process CPU-time ratio to the "
                    "Direct render (default wall; cpu on a shared machine)")
        ->type_name("wall|cpu")
        ->check(CLI::IsMember({"wall", "cpu"}));
    CLI::Option* check =
        sub->add_option("--check", args->check,
                        "judge Auto on measured cases: per case its choice (from the models) "
                        "against the measured front: the time ratio to the cheapest candidate at "
                        "or under its measured error (goal <= 1.2) and whether it is the measured "
                        "best within the budget (repeatable)")
            ->type_name("CSV")
            ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
            ->check(existingFile())
            ->excludes(scene)
            ->excludes(fit);
    sub->add_option("--budget-ratio", args->budgetRatio,
                    "the budget of --check as a multiple of the Direct frame (default 20)")
        ->type_name("R")
        ->check(finiteRange(1e-3, 1e9))
        ->needs(check);
    sub->add_option("--error-tolerance", args->errorTolerance,
                    "--check: predicted errors within this fraction of the least count as equal "
                    "and the cheapest wins (the planner's default 0.1)")
        ->type_name("T")
        ->check(finiteRange(0.0, 0.99))
        ->needs(check);
    sub->add_flag("--cross-validate", args->crossValidate,
                  "--check: judge each case by models fitted on the other cases' rows (leave one "
                  "case out, --ridge R) instead of --models: how Auto fares on a scene its "
                  "models were not fitted on")
        ->needs(check);
    // --check replays the level check on the CSV's block_rel_l1_to_finer column.
    addLevelCheckOptions(*sub, args->levelTolerance, "Level check (SCENE and --check)");
    // --check --measure replays Auto planning with each case's measured errors.
    addMeasureOptions(*sub, args->measure, args->measureOptions, "Measuring (SCENE and --check)");
    sub->add_option("--planned-errors", args->plannedErrors,
                    "--check --measure: Auto plans with the errors of these rows (the same cases "
                    "scored against an independent reference, `evaluate --ref-seed 2`) and is "
                    "judged by --check's, as its own measurement has its own reference "
                    "(repeatable; default: the --check rows' own errors)")
        ->type_name("CSV")
        ->check(existingFile())
        ->needs(check)
        ->group("Measuring (SCENE and --check)");
    sub->add_option("--judged-errors", args->judgedErrors,
                    "--check: judge Auto by the errors and noise floors of these rows (the same "
                    "cases scored against another reference, e.g. a sharper one from `evaluate "
                    "--ref-floor`); costs, features and the level check stay --check's; with "
                    "--cross-validate the left-out models are fitted on these errors too "
                    "(repeatable)")
        ->type_name("CSV")
        ->check(existingFile())
        ->needs(check);
    sub->callback([args] { runPlan(*args); });
}

}  // namespace lucent::cli
