// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli evaluate`: scores the translucency methods against the exact reference on
/// the evaluation suite or on scene files. Parses and prints; the cases, the reference cache,
/// the metrics and the report files are the engine's (lucent/evaluation/).

#include "CliCommon.h"

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>
#include <lucent/evaluation/Evaluate.h>
#include <lucent/evaluation/Report.h>
#include <lucent/evaluation/Suite.h>
#include <lucent/material/Presets.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace lucent::cli {

namespace {

namespace fs = std::filesystem;

std::vector<std::string> splitComma(const std::string& s) {
    std::vector<std::string> out;
    std::string cur;
    for (char c : s + ",") {
        if (c == ',') {
            if (!cur.empty())
                out.push_back(cur);
            cur.clear();
        } else if (c != ' ') {
            cur += c;
        }
    }
    return out;
}

/// "--etas 1.3,1": each a finite relative index in [1, 3] (the range the methods accept).
std::vector<float> parseEtas(const std::vector<std::string>& items) {
    std::vector<float> out;
    for (const std::string& item : items) {
        char* end = nullptr;
        const double v = std::strtod(item.c_str(), &end);
        if (end == item.c_str() || *end != '\0' || !std::isfinite(v) || v < 1.0 || v > 3.0)
            LUCENT_THROW(ValueError, "--etas: '", item,
                         "' is not a relative index of refraction in [1, 3]");
        out.push_back(float(v));
    }
    return out;
}

/// `--report DIR`: the derived reports redrawn from DIR/results.csv and DIR/results.json.
void redrawReports(const std::string& dir) {
    const std::string csv = (fs::path(dir) / "results.csv").string();
    const std::string json = (fs::path(dir) / "results.json").string();
    const std::vector<evaluation::Result> results =
        evaluation::parseResultsCsv(readInputFile(csv, "evaluation results"), csv);
    const evaluation::RunInfo info =
        evaluation::parseRunInfoJson(readInputFile(json, "evaluation run info"), json);
    evaluation::writeDerivedReports(results, info, dir);
    std::printf(
        "%s\nrewrote the summary, the Pareto front and the chart data of %zu results in "
        "%s; charts: cd %s && gnuplot charts.gp\n",
        evaluation::summaryMarkdown(results).c_str(), results.size(), dir.c_str(), dir.c_str());
}

struct EvaluateOptions {
    std::vector<std::string> scenes;
    std::string suite, cases, methods, out, presets, etas, report;
    int refSpp = 256, refSeed = 1, refMaxSpp = 8192, repeats = 3, levels = 3, width = 0, height = 0,
        materialRes = 48;
    double refFloor = 0.0;
    bool subsurfaceOnly = false, json = false, verbose = false, noImages = false;
    const CLI::App* app = nullptr;
    bool has(const std::string& option) const { return app->count(option) > 0; }
};

void runEvaluate(const EvaluateOptions& args, const std::vector<std::string>& argv) {
    if (args.has("--report")) {
        if (argv.size() != 2 && !(argv.size() == 1 && argv[0].rfind("--report=", 0) == 0))
            LUCENT_THROW(ValueError, "--report DIR takes no other option");
        redrawReports(args.report);
        return;
    }
    const bool suite = args.has("--suite");
    if (suite && !args.scenes.empty())
        LUCENT_THROW(ValueError, "give either --suite NAME or SCENE.json files, not both");
    if (!suite && args.scenes.empty())
        LUCENT_THROW(ValueError, "expected --suite NAME or at least one SCENE.json (see --help)");
    if (suite && (args.has("--presets") || args.has("--etas")))
        LUCENT_THROW(ValueError, "--presets and --etas apply to SCENE.json files only");
    if (!suite && args.has("--cases"))
        LUCENT_THROW(ValueError, "--cases applies to --suite only");
    if (!suite && args.has("--material-res"))
        LUCENT_THROW(ValueError,
                     "--material-res applies to --suite only (a scene file has its own "
                     "\"resolution\")");
    if (args.out.empty())
        LUCENT_THROW(ValueError, "missing --out DIR");
    const std::string* outDir = &args.out;
    const std::vector<evaluation::Variant> variants = evaluation::parseVariants(
        args.has("--methods") ? args.methods : evaluation::defaultVariants());

    evaluation::RunOptions options;
    options.outDir = *outDir;
    options.refSpp = args.refSpp;
    options.refSeed = args.refSeed;
    if (args.has("--ref-max-spp") && !args.has("--ref-floor"))
        LUCENT_THROW(ValueError, "--ref-max-spp caps --ref-floor's references: give --ref-floor");
    if (args.has("--ref-floor") && args.refMaxSpp < args.refSpp)
        LUCENT_THROW(ValueError, "--ref-max-spp ", args.refMaxSpp, " is below --ref-spp ",
                     args.refSpp, ", the pilot's samples");
    options.refFloor = args.refFloor;
    options.refMaxSpp = args.refMaxSpp;
    options.repeats = args.repeats;
    options.levels = args.levels;
    options.subsurfaceOnly = args.subsurfaceOnly;
    options.writeImages = !args.noImages;
    const bool json = args.json;
    const bool verbose = args.verbose;
    options.silenceMethods = !verbose;
    FILE* log = json ? stderr : stdout;  // progress; with --json stdout holds the JSON only
    options.progress = [log](const std::string& line) {
        std::fprintf(log, "%s\n", line.c_str());
        std::fflush(log);
    };
    // The methods' own notes (fallbacks, ignored lights): only with --verbose.
    options.methodLog = [verbose](const std::string& m) {
        if (verbose)
            std::fprintf(stderr, "  %s\n", m.c_str());
    };

    // Every case is built first: a bad file or name fails before any long render.
    std::vector<evaluation::EvalCase> cases;
    evaluation::RunInfo info;
    if (suite) {
        evaluation::SuiteOptions so;
        for (const auto& [option, pixels] :
             {std::pair{"--width", args.width}, std::pair{"--height", args.height}})
            if (args.has(option) && (pixels < 8 || pixels > 4096))
                LUCENT_THROW(ValueError, option, ": ", pixels,
                             " is outside [8, 4096], the suite's image sizes");
        if (args.has("--width"))
            so.width = args.width;
        so.height = args.has("--height") ? args.height : args.has("--width") ? so.width : so.height;
        so.materialResolution = args.materialRes;
        so.log = [](const std::string& m) { std::fprintf(stderr, "evaluate: %s\n", m.c_str()); };
        cases =
            evaluation::filterCases(evaluation::buildSuite(args.suite, so), splitComma(args.cases));
        info.suite = args.suite;
    } else {
        std::vector<const MaterialPreset*> presets;
        for (const std::string& name : splitComma(args.presets))
            presets.push_back(&findPreset(name));  // ValueError listing the valid names
        const std::vector<float> etas = parseEtas(splitComma(args.etas));
        if (args.has("--presets") && presets.empty())
            LUCENT_THROW(ValueError, "--presets: no preset given");
        if (args.has("--etas") && etas.empty())
            LUCENT_THROW(ValueError, "--etas: no value given");
        cases =
            evaluation::casesFromSceneFiles(args.scenes, presets, etas, args.width, args.height);
        info.suite = "files";
    }

    std::error_code ec;
    fs::create_directories(*outDir, ec);
    if (ec || !fs::is_directory(*outDir))
        LUCENT_THROW(IoError, "--out ", *outDir, ": cannot create the directory (", ec.message(),
                     ")");

    info.command = "lucent-cli evaluate";
    for (const std::string& a : argv)
        info.command += " " + a;
    info.width = cases.front().scene.camera.width;
    info.height = cases.front().scene.camera.height;
    info.refSpp = options.refSpp;
    info.refSeed = options.refSeed;
    info.refFloor = options.refFloor;
    info.refMaxSpp = options.refFloor > 0 ? options.refMaxSpp : 0;
    info.repeats = options.repeats;
    info.subsurfaceOnly = options.subsurfaceOnly;
    std::vector<evaluation::Result> results;
    for (const evaluation::EvalCase& c : cases) {
        evaluation::CaseRun run = evaluation::evaluateCase(c, variants, options);
        info.cases.push_back(c.name);
        info.referenceSeconds.push_back(run.reference.seconds);
        info.noiseFloors.push_back(run.reference.blockRelL1Floor);
        info.referenceSpp.push_back(run.reference.spp);
        info.skipped.insert(info.skipped.end(), run.skipped.begin(), run.skipped.end());
        for (const std::string& s : run.skipped)
            std::fprintf(stderr, "evaluate: skipped %s\n", s.c_str());
        results.insert(results.end(), run.results.begin(), run.results.end());
    }

    evaluation::writeReports(results, info, *outDir);
    if (json) {
        std::fputs(evaluation::toJson(results, info).c_str(), stdout);
        return;
    }
    std::printf("\n%s", evaluation::summaryMarkdown(results).c_str());
    const fs::path dir(*outDir);
    std::printf(
        "wrote %s, %s, %s, %s and %s (%zu results, %zu skipped); charts: cd %s && "
        "gnuplot charts.gp\n",
        (dir / "results.csv").string().c_str(), (dir / "results.json").string().c_str(),
        (dir / "summary.md").string().c_str(), (dir / "pareto.md").string().c_str(),
        (dir / "charts.gp").string().c_str(), results.size(), info.skipped.size(),
        dir.string().c_str());
}

}  // namespace

void addEvaluateCommand(CLI::App& cli, const CommandContext& context) {
    CLI::App* sub = addCommand(
        cli, "evaluate",
        "run time vs error of the methods against the exact reference (suite or scenes)",
        "usage: lucent-cli evaluate (--suite NAME [--cases F1,F2,...] |\n"
        "                            SCENE.json [SCENE2.json ...]\n"
        "                            [--presets P1,...] [--etas E1,...]) --out DIR\n"
        "                           [--methods M1,M2,...] [--ref-spp N] [--width W] [--height H]\n"
        "                           [--repeats R] [--levels L] [--subsurface-only] [--no-images]\n"
        "                           [--material-res N] [--json] [--verbose]\n"
        "       lucent-cli evaluate --report DIR\n",
        "For each case: the exact path-traced reference with variance and coverage (seed 1,\n"
        "dielectric boundary), cached in DIR by scene hash and reference estimator version, with\n"
        "its noise floor; the Direct render's time (the unit of cost); then each method at a few\n"
        "quality settings, rendered in-process with the functions of `lucent-cli render`. Time:\n"
        "median wall time of R runs after one warm-up, of the whole method call (GL context\n"
        "creation included). Error, over the object-covered pixels in 4x4-pixel blocks of\n"
        "luminance and per channel: block relative L1 and RMSE with the reference noise floor\n"
        "removed in quadrature, the 95th-percentile block error and the mean ratio\n"
        "(docs/evaluation.md). Writes DIR/results.csv (with the planner's scene features per\n"
        "case), results.json, summary.md (best method per case against the goal: block rel. L1\n"
        "<= 0.10, mean ratio 1 +- 0.05), pareto.md, charts.gp with its chart_*.dat (run\n"
        "`gnuplot charts.gp` in DIR for the PNG charts) and, per render, an EXR and a PNG.\n");
    auto args = std::make_shared<EvaluateOptions>();
    args->app = sub;
    sub->add_option("SCENE.json", args->scenes, "scene files to evaluate (instead of --suite)")
        ->check(existingFile());
    sub->add_option("--suite", args->suite,
                    "default (every case of docs/evaluation.md, 64x64) or smoke (two cases at "
                    "32x32 for a quick check)")
        ->type_name("NAME");
    sub->add_option("--cases", args->cases,
                    "only the suite's cases whose name contains one of the entries")
        ->type_name("LIST");
    sub->add_option("--methods", args->methods,
                    "comma-separated METHOD[:VARIANT] (default: each method's default evaluation "
                    "variants; `lucent-cli methods` lists the methods, their variants and quality "
                    "levels, e.g. sslpv:paper, dipole:cpu, dirpole:raw). The reference method "
                    "runs with the reference's seed + 6 (7 by default). A variant this binary or "
                    "case cannot render is skipped "
                    "with a message")
        ->type_name("LIST");
    sub->add_option("--out", args->out, "output directory (created if needed)")->type_name("DIR");
    sub->add_option("--ref-spp", args->refSpp, "reference samples per pixel (default 256)")
        ->type_name("N")
        ->check(CLI::Range(3, 1 << 20));
    sub->add_option("--ref-seed", args->refSeed,
                    "the reference's path-tracer seed (default 1). Another seed is an independent "
                    "estimate of the same image, cached beside the first: evaluating against it "
                    "shows how far each measured error moves with the reference's noise")
        ->type_name("S")
        ->check(CLI::Range(1, 1 << 30));
    sub->add_option("--ref-floor", args->refFloor,
                    "references at a stated noise floor: a case whose --ref-spp reference (the "
                    "pilot) has a block rel. L1 floor above F is rendered again with the samples "
                    "that reach F (the floor falls as 1/sqrt(spp)), at most --ref-max-spp; each "
                    "case reports the floor it reached")
        ->type_name("F")
        ->check(CLI::Range(1e-6, 1.0));
    sub->add_option("--ref-max-spp", args->refMaxSpp,
                    "with --ref-floor: the most samples per pixel a reference gets (default 8192)")
        ->type_name("N")
        ->check(CLI::Range(3, 1 << 20));
    sub->add_option("--width", args->width,
                    "image width (pixels; --suite: default 64, the height follows the width)")
        ->type_name("W")
        ->check(CLI::Range(1, 16384));
    sub->add_option("--height", args->height, "image height (pixels)")
        ->type_name("H")
        ->check(CLI::Range(1, 16384));
    sub->add_option("--material-res", args->materialRes,
                    "--suite: voxels per axis of the cases' painted volumes (default 48; the "
                    "back-lit thin-thick case keeps its file's 128). Other cases, other "
                    "references: the scene hash includes the volume")
        ->type_name("N")
        ->check(CLI::Range(16, 256));
    sub->add_option("--repeats", args->repeats, "timed runs per setting (default 3)")
        ->type_name("R")
        ->check(CLI::Range(1, 1000));
    sub->add_option("--levels", args->levels,
                    "at most L quality settings per method, cheapest first (default 3)")
        ->type_name("L")
        ->check(CLI::Range(1, 16));
    sub->add_option("--presets", args->presets,
                    "scene files: evaluate every scene once per material preset (e.g. "
                    "skin1,marble,wholemilk) on the scene's grid")
        ->type_name("LIST");
    sub->add_option("--etas", args->etas,
                    "scene files: evaluate every scene (and preset) once per relative index of "
                    "refraction in [1, 3]; cases are named <scene>[-<preset>][-eta<E>]")
        ->type_name("LIST");
    sub->add_flag("--subsurface-only", args->subsurfaceOnly,
                  "reference and methods without the surface reflection");
    sub->add_flag("--no-images", args->noImages, "write no EXR/PNG per render");
    sub->add_flag("--json", args->json, "print results.json to stdout (progress goes to stderr)");
    sub->add_flag("--verbose", args->verbose, "keep the methods' own logs on stderr");
    sub->add_option("--report", args->report,
                    "render nothing: rewrite summary.md, pareto.md and the chart data and script "
                    "from DIR/results.csv and DIR/results.json")
        ->type_name("DIR")
        ->check(existingDirectory());
    sub->callback([args, &context] { runEvaluate(*args, context.arguments); });
}

}  // namespace lucent::cli
