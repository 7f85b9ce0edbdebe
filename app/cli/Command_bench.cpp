// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli bench sslpv`: timing of the SSLPV propagation (docs/benchmarks.md, SSLPV)
/// next to a memory-bandwidth floor measured in the same run; `bench sslpv-fit`: the calibrated
/// SSLPV mode's fit; `bench calibrate`: the Auto planner's live costs measured on this machine
/// (lucent/planner/LiveCalibration.h, docs/planner.md "Live costs").

#include "CliCommon.h"

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/planner/LiveCalibration.h>
#include <lucent/sslpv/SslpvBench.h>
#include <lucent/sslpv/SslpvCalibrationFit.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace lucent::cli {

namespace {

// The calibration fit's vocabulary (lucent/sslpv/SslpvCalibrationFit.h): this file only fills its
// settings and prints its rows.
using sslpv::SslpvBetaRow;
using sslpv::SslpvCalibrationFit;
using sslpv::SslpvCalibrationFitSettings;
using sslpv::SslpvFitRow;
using sslpv::SslpvFitWeight;

struct BenchOptions {
    std::string scene = "cube";
    int grid = 32, steps = 8, sh = 1, threads = maxThreads(), repeats = 50;
    bool heterogeneous = false, gl = false, fp16 = false, dense = false, json = false;
};

void runBench(const BenchOptions& args) {
    const int n = args.grid;
    const int steps = args.steps;
    const int order = args.sh;
    const int threads = args.threads;
    const int repeats = args.repeats;
    const bool het = args.heterogeneous;
    const ThreadLimit limit(threads);
    const sslpv::SslpvBenchScene scene = sslpv::parseSslpvBenchScene(args.scene);
    const sslpv::SslpvBenchResult b = sslpv::runSslpvBench({.scene = scene,
                                                            .gridCells = n,
                                                            .steps = steps,
                                                            .order = order,
                                                            .repeats = repeats,
                                                            .heterogeneous = het,
                                                            .dense = args.dense,
                                                            .gl = args.gl,
                                                            .fp16 = args.fp16});
    if (args.gl)
        std::printf(
            "%sGL %s (%s): propagation %.3f ms GPU timer, %.3f ms wall per propagate (input "
            "diff/upload %.3f ms), read-back when asked %.3f ms\n",
            args.json ? "# " : "", b.glRenderer.c_str(), args.fp16 ? "fp16" : "fp32", b.glGpuMs,
            b.glWallMs, b.glUploadMs, b.glReadbackMs);

    const double msSolve = b.solveMs, cpuPerSolve = b.cpuSolveMs;
    const double msSteps = b.stepsMs;
    const double msPerStep = msSteps / steps;
    const double floorPerStep = b.floorStepMs;
    const double paperMs = 1.67;  // GTX 580, 32³, 8 steps, heterogeneous (Table 1, Fig. 6)
    if (args.json) {
        std::printf(
            "{\"benchmark\": \"sslpv\", \"scene\": \"%s\", \"grid\": %d, \"steps\": %d, "
            "\"sh_order\": %d, "
            "\"heterogeneous\": %s, \"dense\": %s, \"threads\": %d, \"repeats\": %d, "
            "\"brick_count\": %d, \"active_bricks_per_step\": %.1f, "
            "\"cells_per_step\": %.0f, "
            "\"ms_per_solve\": %.4f, "
            "\"cpu_ms_per_solve\": %.4f, "
            "\"ms_propagation\": %.4f, \"ms_per_step\": %.5f, \"floor_ms_per_step\": %.5f, "
            "\"ratio_to_floor\": %.3f, \"gl_gpu_ms\": %.4f, \"gl_total_ms\": %.4f, "
            "\"gl_readback_ms\": %.4f, "
            "\"paper_ms_gtx580_32_8_het\": %.2f}\n",
            sslpv::sslpvBenchSceneName(scene), n, steps, order, het ? "true" : "false",
            args.dense ? "true" : "false", threads, repeats, b.brickCount, b.activeBricks,
            b.cellsPerStep, msSolve, cpuPerSolve, msSteps, msPerStep, floorPerStep,
            msPerStep / floorPerStep, b.glGpuMs, b.glWallMs, b.glReadbackMs, paperMs);
    } else {
        std::printf(
            "SSLPV CPU propagation: scene %s, %d^3 cells, %d steps, SH order %d, %s, %s, %d "
            "thread(s)\n",
            sslpv::sslpvBenchSceneName(scene), n, steps, order,
            het ? "heterogeneous" : "homogeneous", args.dense ? "dense" : "active bricks", threads);
        std::printf("  bricks (%dx%dx%d cells) per step: %.1f of %d active, %.0f cells computed\n",
                    sslpv::SSLPV_BRICK_X, sslpv::SSLPV_BRICK_Y, sslpv::SSLPV_BRICK_Z,
                    b.activeBricks, b.brickCount, b.cellsPerStep);
        std::printf("  median over %d solves after warm-up\n", repeats);
        std::printf("  solve (factors + propagation): %.3f ms wall, %.3f ms CPU (all threads)\n",
                    msSolve, cpuPerSolve);
        std::printf("  propagation steps:             %.3f ms (%.4f ms/step)\n", msSteps,
                    msPerStep);
        std::printf("  bandwidth floor:               %.4f ms/step  -> ratio %.2f\n", floorPerStep,
                    msPerStep / floorPerStep);
        std::printf("  paper (GTX 580, 32^3, 8 steps, heterogeneous): %.2f ms\n", paperMs);
    }
}

// ---------------------------------------------------------------------------------------------
// `lucent-cli bench sslpv-fit`: the calibrated mode's fit (lucent/sslpv/SslpvCalibrationFit.h,
// docs/methods/sslpv.md); parses and prints only.

struct FitOptions {
    SslpvCalibrationFitSettings settings;
    SslpvFitWeight weight = SslpvFitWeight::Transport;
    float gain = 1.f;
    int iterations = 0;  ///< 0: the mode's default
    bool search = false, solveBeta = false;
};

const char* weightName(SslpvFitWeight w) {
    switch (w) {
        case SslpvFitWeight::Linear:
            return "linear";
        case SslpvFitWeight::Diffusion:
            return "diffusion";
        case SslpvFitWeight::Transport:
            break;
    }
    return "transport";
}

void runFit(const FitOptions& args) {
    SslpvCalibrationFitSettings s = args.settings;
    const std::string param = weightName(args.weight);
    if (args.solveBeta) {
        const float gain = args.gain;
        std::printf(
            "| dx*sigma_t | alpha' | beta* | beta*/(1-alpha') | sigma_tr dx | steps |\n"
            "|---|---|---|---|---|---|\n");
        solveSslpvBeta(s, double(gain), args.iterations ? args.iterations : 10,
                       [](const SslpvBetaRow& r) {
                           std::printf("| %.2f | %.3f | %.5f | %.4f | %.4f | %d |\n",
                                       double(r.fitCase.cellMfp), double(r.fitCase.albedo), r.beta,
                                       r.betaPerAbsorption, r.transportCell, r.steps);
                           std::fflush(stdout);
                       });
        return;
    }
    if (args.search) {
        s.search = args.weight;
        s.iterations = args.iterations ? args.iterations : 12;
        s.onSearchStep = [&param](double w, double rmsLog) {
            std::printf("# search: %s %.5f -> rms log %.5f\n", param.c_str(), w, rmsLog);
            std::fflush(stdout);
        };
    }

    const SslpvCalibrationFit r = fitSslpvCalibration(s);
    std::printf(
        "SSLPV calibrated-mode fit: thick slab %d^3 cells, SH order %d, eta %.2f, "
        "g = 0\n",
        s.gridCells, s.order, double(s.eta));
    std::printf(
        "  model: beta = %.5f sigma_a dx + %.5f sigma_tr dx + %.5f (sigma_tr dx)^2 + "
        "%.5f sigma_a/sigma_t + %.5f sigma_tr/sigma_t, gain G = %.5f\n",
        double(r.calibration.linear), double(r.calibration.transport),
        double(r.calibration.diffusion), double(r.calibration.perStep),
        double(r.calibration.perStepTransport), r.gain);
    std::printf("  target: classical dipole F_t(0) R_d / pi (Jensen 2001)\n");
    std::printf(
        "| dx*sigma_t | alpha' | dipole R_d | target L/E (1/sr) | SSLPV G*L/E | "
        "residual | steps |\n|---|---|---|---|---|---|---|\n");
    for (const SslpvFitRow& row : r.rows)
        std::printf("| %.2f | %.3f | %.4f | %.5f | %.5f | %+.1f %% | %d |\n",
                    double(row.fitCase.cellMfp), double(row.fitCase.albedo), row.dipoleReflectance,
                    row.target, row.fitted, 100.0 * row.residual, row.steps);
    std::printf("  RMS log residual %.4f, max |residual| %.1f %%\n", r.rmsLog, 100.0 * r.maxAbsRel);
}

void addSslpvBench(CLI::App& bench) {
    CLI::App* sub = addCommand(
        bench, "sslpv", "time the SSLPV propagation against a bandwidth floor",
        "usage: lucent-cli bench sslpv [--scene cube|sphere|shell|spot] [--grid N] [--steps K]\n"
        "                              [--sh 1|2] [--heterogeneous] [--dense] [--threads T]\n"
        "                              [--repeats R] [--gl [--fp16]] [--json]\n",
        "Times repeated SSLPV solves (per-cell factors + propagation) on an N^3 grid of 1 mm\n"
        "cells after 3 warm-up solves, and prints medians next to a memory-bandwidth floor\n"
        "measured in the same run (streaming the same planes: copy + accumulate, per step).\n");
    auto args = std::make_shared<BenchOptions>();
    sub->add_option("--scene", args->scene,
                    "cube: every cell material, top face lit (the paper's set-up, default); "
                    "sphere: ball of radius 0.45 N with sinks lit from above; shell: hollow ball "
                    "0.38-0.45 N; spot: cube lit on a 4x4-cell spot")
        ->type_name("S");
    sub->add_option("--grid", args->grid, "cells per axis (default 32)")
        ->type_name("N")
        ->check(CLI::Range(4, 256));
    sub->add_option("--steps", args->steps, "propagation steps (default 8)")
        ->type_name("K")
        ->check(CLI::Range(1, 4096));
    sub->add_option("--sh", args->sh, "spherical-harmonics order: 4 or 9 coefficients (default 1)")
        ->type_name("1|2")
        ->check(CLI::Range(1, 2));
    sub->add_flag("--heterogeneous", args->heterogeneous,
                  "random per-cell material (per-cell factor arrays)");
    sub->add_flag("--dense", args->dense,
                  "compute every cell of the object's box every step (no active-brick skipping: "
                  "the paper's dense GPU work)");
    sub->add_option("--threads", args->threads, "worker threads (default: all)")
        ->type_name("T")
        ->check(CLI::Range(1, 256));
    sub->add_option("--repeats", args->repeats, "timed solves (default 50)")
        ->type_name("R")
        ->check(CLI::Range(3, 100000));
    CLI::Option* gl = sub->add_flag("--gl", args->gl,
                                    "also time the GL 4.5 compute propagation (headless EGL "
                                    "context; GPU timer queries; persistent buffers, so repeats "
                                    "upload nothing; the read-back is timed separately), fp32 "
                                    "grids");
    sub->add_flag("--fp16", args->fp16, "with --gl: fp16 grids")->needs(gl);
    sub->add_flag("--json", args->json,
                  "one JSON object: ms_per_solve, ms_propagation, ms_per_step, floor_ms_per_step, "
                  "ratio_to_floor, brick_count, active_bricks_per_step, cells_per_step "
                  "(gl_gpu_ms, gl_total_ms, gl_readback_ms: 0 without --gl)");
    sub->callback([args] { runBench(*args); });
}

void addSslpvFit(CLI::App& bench) {
    CLI::App* sub = addCommand(
        bench, "sslpv-fit", "fit the calibrated SSLPV mode against the classical dipole",
        "usage: lucent-cli bench sslpv-fit [--grid N] [--sh 1|2] [--eta E] [--linear U]\n"
        "                                  [--transport T] [--diffusion K] [--per-step P]\n"
        "                                  [--per-step-transport Q]\n"
        "                                  [--search [--fit linear|transport|diffusion]]\n"
        "                                  [--solve-beta [--gain G]] [--iterations I]\n",
        "Fit of the calibrated SSLPV mode (docs/methods/sslpv.md): thick slabs (N^3 grid, default\n"
        "48) for alpha' in {0.3 .. 0.99} and cell sizes {0.5, 1, 2, 4} mean free paths; per-step\n"
        "absorption beta = U sigma_a dx + T sigma_tr dx + K (sigma_tr dx)^2 + P sigma_a/sigma_t\n"
        "+ Q sigma_tr/sigma_t (each weight defaults to the shipped constant); prints the optimal\n"
        "radiance gain G and the residual of each case against the classical dipole.\n");
    auto args = std::make_shared<FitOptions>();
    SslpvCalibrationFitSettings& s = args->settings;
    sub->add_option("--grid", s.gridCells, "cells per axis of the slab grid (default 48)")
        ->type_name("N")
        ->check(CLI::Range(16, 128));
    sub->add_option("--sh", s.order, "spherical-harmonics order (default 1)")
        ->type_name("1|2")
        ->check(CLI::Range(1, 2));
    sub->add_option("--eta", s.eta, "relative index of refraction (default 1.3)")
        ->type_name("E")
        ->check(finiteRange(1, 3));
    const struct {
        const char* name;
        float sslpv::SslpvCalibration::*weight;
        const char* help;
    } weights[] = {
        {"--linear", &sslpv::SslpvCalibration::linear, "U, the weight of sigma_a dx"},
        {"--transport", &sslpv::SslpvCalibration::transport, "T, the weight of sigma_tr dx"},
        {"--diffusion", &sslpv::SslpvCalibration::diffusion, "K, the weight of (sigma_tr dx)^2"},
        {"--per-step", &sslpv::SslpvCalibration::perStep, "P, the weight of sigma_a/sigma_t"},
        {"--per-step-transport", &sslpv::SslpvCalibration::perStepTransport,
         "Q, the weight of sigma_tr/sigma_t"}};
    for (const auto& w : weights)
        sub->add_option(w.name, s.calibration.*w.weight,
                        std::string(w.help) + " (default: the shipped constant)")
            ->type_name("W")
            ->check(finiteRange(0, 100));
    CLI::Option* search =
        sub->add_flag("--search", args->search,
                      "fit one weight by golden-section search (log scale over [0.02, 5], I "
                      "iterations, default 12) minimising the RMS log residual");
    addChoiceOption<SslpvFitWeight>(*sub, "--fit", args->weight,
                                    {{"linear", SslpvFitWeight::Linear},
                                     {"transport", SslpvFitWeight::Transport},
                                     {"diffusion", SslpvFitWeight::Diffusion}},
                                    "the weight --search fits (default transport)")
        ->needs(search);
    CLI::Option* solveBeta =
        sub->add_flag("--solve-beta", args->solveBeta,
                      "per case, bisect the per-step absorption beta* that matches the dipole "
                      "with gain G, I iterations (default 10): the fit data")
            ->excludes(search);
    sub->add_option("--gain", args->gain, "--solve-beta: the radiance gain G (default 1)")
        ->type_name("G")
        ->check(finiteRange(1e-3, 1e3))
        ->needs(solveBeta);
    sub->add_option("--iterations", args->iterations,
                    "search or bisection iterations (--search: at most 100, --solve-beta: 40)")
        ->type_name("I")
        ->check(CLI::Range(1, 100));
    sub->callback([args] { runFit(*args); });
}

struct CalibrateOptions {
    std::string output;  // empty: planner::userLiveCostsPath()
    std::string viewport = "640x360";
    std::vector<std::string> candidates;  // METHOD@SETTING; empty: the shipped table's
    planner::LiveCalibrationOptions calibration;
};

void runCalibrate(const CalibrateOptions& args) {
    planner::LiveCalibrationOptions o = args.calibration;
    int w = 0, h = 0;
    char tail = 0;
    if (std::sscanf(args.viewport.c_str(), "%dx%d%c", &w, &h, &tail) != 2)
        LUCENT_THROW(ValueError, "bench calibrate: --viewport expects WxH (e.g. 640x360), got '",
                     args.viewport, "'");
    o.viewportWidth = w;
    o.viewportHeight = h;
    for (const std::string& c : args.candidates) {
        const size_t at = c.find('@');
        if (at == std::string::npos || at == 0 || at + 1 == c.size())
            LUCENT_THROW(ValueError, "bench calibrate: --candidate expects METHOD@SETTING (e.g. ",
                         "'sslpv:diffusion@grid 32'), got '", c, "'");
        o.candidates.push_back({c.substr(0, at), c.substr(at + 1), 0.0});
    }
    const std::string path = args.output.empty() ? planner::userLiveCostsPath() : args.output;
    if (path.empty())
        LUCENT_THROW(ValueError, "bench calibrate: neither ", planner::LIVE_COSTS_ENV,
                     ", XDG_CONFIG_HOME nor HOME is set: give the file with -o PATH");
    o.progress = [](const planner::LiveCalibrationProgress& p) {
        printProgressBar(p.total > 0 ? double(p.done) / p.total : 1.0,
                         p.next.empty() ? "done" : p.next);
    };
    const planner::LiveCalibration c = planner::calibrateLiveCosts(o);
    std::fprintf(stderr, "\n");
    const planner::LiveCosts& shipped = planner::defaultLiveCosts();
    std::printf(
        "%s\nunit: a Direct frame, %.2f ms (median of %zu runs; shipped: %.2f ms on %s)\n\n",
        c.costs.source.c_str(), c.costs.directMs, c.rows.size() * size_t(o.rounds),
        shipped.directMs,
        shipped.renderer.empty() ? "the shipped table's machine" : shipped.renderer.c_str());
    std::printf(
        "| candidate | stroke → frame (ms) | ratio | ratio per round | shipped ratio | "
        "ratio / shipped |\n|---|---:|---:|---|---:|---:|\n");
    for (const planner::LiveCalibrationRow& r : c.rows) {
        double shippedRatio = 0.0;
        for (const planner::LiveCost& s : shipped.entries)
            if (s.method == r.cost.method && s.setting == r.cost.setting)
                shippedRatio = s.strokeRatio;
        std::string rounds;
        for (double x : r.roundRatios) {
            char v[32];
            std::snprintf(v, sizeof v, "%s%.2f", rounds.empty() ? "" : " ", x);
            rounds += v;
        }
        std::printf("| %s %s | %.1f | %.2f | %s | ", r.cost.method.c_str(), r.cost.setting.c_str(),
                    r.strokeMs, r.cost.strokeRatio, rounds.c_str());
        if (shippedRatio > 0)
            std::printf("%.2f | %.2f |\n", shippedRatio, r.cost.strokeRatio / shippedRatio);
        else
            std::printf("– | – |\n");
    }
    planner::saveLiveCosts(c.costs, path);
    std::printf(
        "\nwritten %s (the app's Auto plans with it from its next start, or at once "
        "after Edit ▸ Preferences ▸ Calibrate Live Costs)\n",
        path.c_str());
}

void addCalibrate(CLI::App& bench) {
    CLI::App* sub = addCommand(
        bench, "calibrate", "measure the Auto planner's live costs on this machine",
        "usage: lucent-cli bench calibrate [-o PATH] [--viewport WxH] [--strokes N]\n"
        "                                  [--rounds R] [--scale S]\n"
        "                                  [--candidate METHOD@SETTING ...]\n",
        "Measures what Auto plans the live preview with (docs/planner.md, \"Live costs\"): for\n"
        "each candidate of the shipped table, on the default scene at the app's default preview\n"
        "settings, the stroke -> frame time of the live method (paint strokes as the app's\n"
        "latency harness paints them, on a headless OpenGL context) over the render time of a\n"
        "Direct frame measured just before it; the median of R rounds. Prints them next to the\n"
        "shipped ratios and writes the file atomically, by default to the user's calibration\n"
        "file ($LUCENT_LIVE_COSTS, else $XDG_CONFIG_HOME/lucent/live_costs.json, else\n"
        "~/.config/lucent/live_costs.json), which the app's Auto then plans with.\n");
    auto args = std::make_shared<CalibrateOptions>();
    sub->add_option("-o,--output", args->output,
                    "the live costs file to write (default: the user's calibration file)")
        ->type_name("PATH");
    sub->add_option("--viewport", args->viewport,
                    "the viewport in widget pixels, rendered at --scale (default 640x360, the "
                    "shipped table's)")
        ->type_name("WxH");
    sub->add_option("--strokes", args->calibration.strokes,
                    "timed strokes per run, after one warm-up stroke (default 8)")
        ->type_name("N")
        ->check(CLI::Range(1, 1000));
    sub->add_option("--rounds", args->calibration.rounds,
                    "runs of every candidate, each after its own Direct run; the ratio is their "
                    "median (default 3)")
        ->type_name("R")
        ->check(CLI::Range(1, 100));
    sub->add_option("--candidate", args->candidates,
                    "measure this candidate instead of the shipped table's, as METHOD@SETTING "
                    "(a method variant of `lucent-cli methods` and one of its quality levels, "
                    "e.g. 'sslpv:diffusion@grid 32'); repeatable")
        ->type_name("METHOD@SETTING");
    sub->add_option("--scale", args->calibration.resolutionScale,
                    "rendered pixels per viewport pixel per axis (default 0.5, the app's half "
                    "resolution)")
        ->type_name("S")
        ->check(finiteRange(0.05, 1));
    sub->callback([args] { runCalibrate(*args); });
}

}  // namespace

void addBenchCommand(CLI::App& cli, const CommandContext&) {
    CLI::App* bench = addCommand(
        cli, "bench",
        "time the SSLPV propagation against a bandwidth floor; fit its calibrated mode; "
        "calibrate Auto's live costs",
        "usage: lucent-cli bench sslpv [options]       (lucent-cli bench sslpv --help)\n"
        "       lucent-cli bench sslpv-fit [options]   (lucent-cli bench sslpv-fit --help)\n"
        "       lucent-cli bench calibrate [options]   (lucent-cli bench calibrate --help)\n",
        "");
    bench->require_subcommand(1);
    addSslpvBench(*bench);
    addSslpvFit(*bench);
    addCalibrate(*bench);
}

}  // namespace lucent::cli
