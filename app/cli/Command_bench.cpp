// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli bench sslpv`: timing of the SSLPV propagation (docs/benchmarks.md, SSLPV)
/// next to a memory-bandwidth floor measured in the same run.

#include "CliArgs.h"

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Timer.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/sslpv/SslpvBench.h>
#include <lucent/sslpv/SslpvCalibrationFit.h>
#include <lucent/sslpv/SslpvGl.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

namespace lucent::cli {

namespace {

/// Process CPU time (all threads), ms: unlike wall time, not inflated when the machine is
/// shared and this process waits for a core.
double cpuMs() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

int runFit(const Args& args);

int runBench(const std::vector<std::string>& argv) {
    const Args args(
        argv,
        {"grid", "steps", "sh", "threads", "repeats", "eta", "linear", "diffusion", "iterations",
         "transport", "fit", "gain", "per-step", "per-step-transport", "scene"},
        {"heterogeneous", "gl", "fp16", "dense", "json", "search", "solve-beta"});
    if (args.positional().size() == 1 && args.positional().front() == "sslpv-fit")
        return runFit(args);
    if (args.positional().size() != 1 || args.positional().front() != "sslpv")
        LUCENT_THROW(ValueError, "expected the benchmark name 'sslpv' or 'sslpv-fit' (see --help)");
    const int n = args.intOr("grid", 32, 4, 256);
    const int steps = args.intOr("steps", 8, 1, 4096);
    const int order = args.intOr("sh", 1, 1, 2);
    const int threads = args.intOr("threads", maxThreads(), 1, 256);
    const int repeats = args.intOr("repeats", 50, 3, 100000);
    const bool het = args.has("heterogeneous");
    const bool gl = args.has("gl");
    if (args.has("fp16") && !gl)
        LUCENT_THROW(ValueError, "--fp16 needs --gl");
    const ThreadLimit limit(threads);
    const SslpvBenchScene scene = parseSslpvBenchScene(args.valueOr("scene", "cube"));

    SslpvBenchSetup setup = makeSslpvBenchSetup(scene, n, het);
    SslpvSolver solver({.order = order,
                        .maxSteps = steps,
                        .skipAccumulateSteps = 0,
                        .removeExitant = setup.sinks,
                        .skipEmptySlices = !args.has("dense")});
    solver.setMaterial(setup.material, setup.eta);
    solver.setInjectionSamples(std::move(setup.texels));

    // Warm-up, then repeated re-propagations (what a paint stroke triggers).
    for (int i = 0; i < 3; ++i) {
        solver.markMaterialDirty();
        solver.solve();
    }
    std::vector<double> solveMs, stepsMs;
    const double cpu0 = cpuMs();
    for (int i = 0; i < repeats; ++i) {
        solver.markMaterialDirty();
        const Timer t;
        solver.solve();
        solveMs.push_back(t.elapsedMs());
        stepsMs.push_back(solver.stats().stepsMs);
    }
    const double cpuPerSolve = (cpuMs() - cpu0) / repeats;

    // Bandwidth floor, same run, same threads: the least traffic one dense step can have
    // without the stencil (SslpvBench.h: stream the source planes into the destination and
    // add them into the accumulation planes, plus the factor planes when heterogeneous).
    const double floorMs = sslpvBandwidthFloorMs(n, order, het, steps, repeats);
    const SslpvStats& st = solver.stats();
    double activeMean = 0.0;
    for (int a : st.activeBricksPerStep)
        activeMean += a;
    activeMean /= std::max<size_t>(st.activeBricksPerStep.size(), 1);
    const double cellsPerStep = double(st.cellsComputed) / std::max(st.stepsUsed, 1);

    // GL compute path: the same propagation on the GPU (injection and factors from the CPU).
    double glGpuMs = 0.0, glCpuMs = 0.0, glReadbackMs = 0.0;
    if (gl) {
        std::string reason;
        if (!gpu::GlContext::isHeadlessAvailable(&reason))
            LUCENT_THROW(GpuError, "--gl: no headless OpenGL 4.5 context: ", reason);
        auto ctx = gpu::GlContext::createHeadless();
        SslpvGlPropagator prop(args.has("fp16") ? SslpvGlStorage::Float16
                                                : SslpvGlStorage::Float32);
        const int glRepeats = std::max(3, std::min(repeats, 10));  // llvmpipe is slow
        prop.propagate(solver);                                    // warm-up (shader JIT)
        // Steady state: persistent buffers, nothing changed to upload, no read-back; then the
        // read-back a CPU consumer would add, timed separately.
        std::vector<double> g, c, r, u;
        for (int i = 0; i < glRepeats; ++i) {
            const Timer wall;
            prop.propagate(solver);
            c.push_back(wall.elapsedMs());
            g.push_back(prop.timings().propagateGpuMs);
            u.push_back(prop.timings().uploadCpuMs);
            (void)prop.accumulation();
            r.push_back(prop.timings().readbackCpuMs);
        }
        glGpuMs = median(g);
        glCpuMs = median(c);
        glReadbackMs = median(r);
        prop.destroy();
        std::printf(
            "%sGL %s (%s): propagation %.3f ms GPU timer, %.3f ms wall per propagate (input "
            "diff/upload %.3f ms), read-back when asked %.3f ms\n",
            args.has("json") ? "# " : "", ctx->renderer().c_str(),
            args.has("fp16") ? "fp16" : "fp32", glGpuMs, glCpuMs, median(u), glReadbackMs);
    }

    const double msSolve = median(solveMs);
    const double msSteps = median(stepsMs);
    const double msPerStep = msSteps / steps;
    const double floorPerStep = floorMs / steps;
    const double paperMs = 1.67;  // GTX 580, 32³, 8 steps, heterogeneous (Table 1, Fig. 6)
    if (args.has("json")) {
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
            sslpvBenchSceneName(scene), n, steps, order, het ? "true" : "false",
            args.has("dense") ? "true" : "false", threads, repeats, st.brickCount, activeMean,
            cellsPerStep, msSolve, cpuPerSolve, msSteps, msPerStep, floorPerStep,
            msPerStep / floorPerStep, glGpuMs, glCpuMs, glReadbackMs, paperMs);
    } else {
        std::printf(
            "SSLPV CPU propagation: scene %s, %d^3 cells, %d steps, SH order %d, %s, %s, %d "
            "thread(s)\n",
            sslpvBenchSceneName(scene), n, steps, order, het ? "heterogeneous" : "homogeneous",
            args.has("dense") ? "dense" : "active bricks", threads);
        std::printf("  bricks (%dx%dx%d cells) per step: %.1f of %d active, %.0f cells computed\n",
                    SSLPV_BRICK_X, SSLPV_BRICK_Y, SSLPV_BRICK_Z, activeMean, st.brickCount,
                    cellsPerStep);
        std::printf("  median over %d solves after warm-up\n", repeats);
        std::printf("  solve (factors + propagation): %.3f ms wall, %.3f ms CPU (all threads)\n",
                    msSolve, cpuPerSolve);
        std::printf("  propagation steps:             %.3f ms (%.4f ms/step)\n", msSteps,
                    msPerStep);
        std::printf("  bandwidth floor:               %.4f ms/step  -> ratio %.2f\n", floorPerStep,
                    msPerStep / floorPerStep);
        std::printf("  paper (GTX 580, 32^3, 8 steps, heterogeneous): %.2f ms\n", paperMs);
    }
    return 0;
}

// ---------------------------------------------------------------------------------------------
// `lucent-cli bench sslpv-fit`: the calibrated mode's fit (lucent/sslpv/SslpvCalibrationFit.h,
// docs/methods/sslpv.md); parses and prints only.

int runFit(const Args& args) {
    SslpvCalibrationFitSettings s;
    s.gridCells = args.intOr("grid", 48, 16, 128);
    s.order = args.intOr("sh", 1, 1, 2);
    s.eta = args.floatOr("eta", 1.3f, 1.f, 3.f);
    if (args.value("linear"))
        s.calibration.linear = args.floatOr("linear", 0.f, 0.f, 100.f);
    if (args.value("diffusion"))
        s.calibration.diffusion = args.floatOr("diffusion", 0.f, 0.f, 100.f);
    if (args.value("transport"))
        s.calibration.transport = args.floatOr("transport", 0.f, 0.f, 100.f);
    if (args.value("per-step"))
        s.calibration.perStep = args.floatOr("per-step", 0.f, 0.f, 100.f);
    if (args.value("per-step-transport"))
        s.calibration.perStepTransport = args.floatOr("per-step-transport", 0.f, 0.f, 100.f);
    // Which weight --search fits (the others stay as given).
    const std::string param = args.valueOr("fit", "transport");
    SslpvFitWeight weight = SslpvFitWeight::Transport;
    if (param == "linear")
        weight = SslpvFitWeight::Linear;
    else if (param == "diffusion")
        weight = SslpvFitWeight::Diffusion;
    else if (param != "transport")
        LUCENT_THROW(ValueError, "--fit: '", param, "' is not linear, transport or diffusion");

    if (args.has("solve-beta")) {
        const float gain = args.floatOr("gain", 1.f, 1e-3f, 1e3f);
        std::printf(
            "| dx*sigma_t | alpha' | beta* | beta*/(1-alpha') | sigma_tr dx | steps |\n"
            "|---|---|---|---|---|---|\n");
        solveSslpvBeta(s, double(gain), args.intOr("iterations", 10, 1, 40),
                       [](const SslpvBetaRow& r) {
                           std::printf("| %.2f | %.3f | %.5f | %.4f | %.4f | %d |\n",
                                       double(r.fitCase.cellMfp), double(r.fitCase.albedo), r.beta,
                                       r.betaPerAbsorption, r.transportCell, r.steps);
                           std::fflush(stdout);
                       });
        return 0;
    }
    if (args.has("search")) {
        s.search = weight;
        s.iterations = args.intOr("iterations", 12, 1, 100);
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
    return 0;
}

}  // namespace

const Command benchCommand{
    "bench", "time the SSLPV propagation against a bandwidth floor; fit its calibrated mode",
    "usage: lucent-cli bench sslpv [--scene cube|sphere|shell|spot] [--grid N] [--steps K]\n"
    "                              [--sh 1|2] [--heterogeneous] [--dense] [--threads T]\n"
    "                              [--repeats R] [--gl [--fp16]] [--json]\n"
    "\n"
    "Times repeated SSLPV solves (per-cell factors + propagation) on an N^3 grid of 1 mm\n"
    "cells after 3 warm-up solves, and prints medians next to a memory-bandwidth floor\n"
    "measured in the same run (streaming the same planes: copy + accumulate, per step).\n"
    "\n"
    "  --scene S         cube: every cell material, top face lit (the paper's set-up,\n"
    "                    default); sphere: ball of radius 0.45 N with sinks lit from above;\n"
    "                    shell: hollow ball 0.38-0.45 N; spot: cube lit on a 4x4-cell spot\n"
    "  --grid N          cells per axis, [4, 256] (default 32)\n"
    "  --steps K         propagation steps, [1, 4096] (default 8)\n"
    "  --sh 1|2          spherical-harmonics order: 4 or 9 coefficients (default 1)\n"
    "  --heterogeneous   random per-cell material (per-cell factor arrays)\n"
    "  --dense           compute every cell of the object's box every step (no active-brick\n"
    "                    skipping: the paper's dense GPU work)\n"
    "  --threads T       worker threads (default: all)\n"
    "  --repeats R       timed solves (default 50)\n"
    "  --gl              also time the GL 4.5 compute propagation (headless EGL context;\n"
    "                    GPU timer queries; persistent buffers, so repeats upload nothing;\n"
    "                    the read-back is timed separately), fp32 grids\n"
    "  --fp16            with --gl: fp16 grids\n"
    "  --json            one JSON object: ms_per_solve, ms_propagation, ms_per_step,\n"
    "                    floor_ms_per_step, ratio_to_floor, brick_count,\n"
    "                    active_bricks_per_step, cells_per_step (gl_gpu_ms, gl_total_ms,\n"
    "                    gl_readback_ms: 0 without --gl)\n"
    "\n"
    "usage: lucent-cli bench sslpv-fit [--grid N] [--sh 1|2] [--eta E] [--linear U]\n"
    "                                  [--transport T] [--diffusion K] [--per-step P]\n"
    "                                  [--per-step-transport Q]\n"
    "                                  [--search [--fit linear|transport|diffusion]]\n"
    "                                  [--solve-beta [--gain G]] [--iterations I]\n"
    "\n"
    "Fit of the calibrated SSLPV mode (docs/methods/sslpv.md): thick slabs (N^3 grid, default\n"
    "48) for alpha' in {0.3 .. 0.99} and cell sizes {0.5, 1, 2, 4} mean free paths; per-step\n"
    "absorption beta = U sigma_a dx + T sigma_tr dx + K (sigma_tr dx)^2 + P sigma_a/sigma_t\n"
    "+ Q sigma_tr/sigma_t (each weight defaults to the shipped constant); prints the optimal\n"
    "radiance gain G and the residual of each case against the classical dipole.\n"
    "  --search       fit one weight (default transport) by golden-section search (log scale\n"
    "                 over [0.02, 5], I iterations, default 12) minimising the RMS log residual\n"
    "  --solve-beta   per case, bisect the per-step absorption beta* that matches the dipole\n"
    "                 with gain G (default 1), I iterations (default 10): the fit data\n",
    &runBench};

}  // namespace lucent::cli
