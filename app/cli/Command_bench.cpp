// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli bench sslpv`: timing of the SSLPV propagation (docs/benchmarks.md, SSLPV)
/// next to a memory-bandwidth floor measured in the same run.

#include "CliArgs.h"

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Random.h>
#include <lucent/core/Timer.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/sslpv/SslpvGl.h>
#include <lucent/sslpv/SslpvRenderer.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <cstring>
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

/// The paper's configuration (§5, Table 1): every cell of the N³ grid is material and is
/// propagated (no sinks), light injected on the top face. Heterogeneous: per-cell σt, σs′, g
/// drawn from a seeded RNG, so the per-cell factor arrays are read every step.
CoarseMaterial benchMaterial(int n, bool heterogeneous) {
    CoarseMaterial m;
    m.spec.resolution = n;
    m.spec.voxelSize = 1.f;
    const size_t count = m.spec.voxelCount();
    m.insideFraction.assign(count, 1.f);
    Pcg32 rng(1234);
    for (int c = 0; c < 3; ++c) {
        m.sigma_t[c].assign(count, 1.f);
        m.sigma_s[c].assign(count, 0.8f);
        m.g[c].assign(count, 0.2f);
        if (heterogeneous)
            for (size_t k = 0; k < count; ++k) {
                m.sigma_t[c][k] = 0.5f + 1.5f * rng.uniform();
                m.sigma_s[c][k] = m.sigma_t[c][k] * rng.uniform();
                m.g[c][k] = 1.6f * rng.uniform() - 0.8f;
            }
    }
    m.homogeneous = !heterogeneous;
    return m;
}

int runBench(const std::vector<std::string>& argv) {
    const Args args(argv, {"grid", "steps", "sh", "threads", "repeats"},
                    {"heterogeneous", "gl", "fp16", "dense", "json"});
    if (args.positional().size() != 1 || args.positional().front() != "sslpv")
        LUCENT_THROW(ValueError, "expected the benchmark name 'sslpv' (see --help)");
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

    SslpvSolver solver({.order = order,
                        .maxSteps = steps,
                        .skipAccumulateSteps = 0,
                        .removeExitant = false,
                        .skipEmptySlices = !args.has("dense")});
    solver.setMaterial(benchMaterial(n, het), 1.3f);
    std::vector<SslpvInjectionSample> texels;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            texels.push_back({Point3f(x + 0.5f, y + 0.5f, float(n)), Normal3f(0, 0, 1),
                              glm::normalize(Vector3f(0.3f, 0.1f, -1.f)), Rgb(1.f)});
    solver.setInjectionSamples(std::move(texels));

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

    // Bandwidth floor, same run, same threads: the least traffic one step can have without the
    // stencil — stream the source planes into the destination (read + write) and add them into
    // the accumulation planes (read + read + write), plus reading the factor planes when
    // heterogeneous. Same plane sizes as the solver's grids.
    const size_t plane = size_t(n + 2) * (n + 2) * (n + 2);
    const size_t planes = size_t(3) * shCount(order);
    const size_t factorPlanes = het ? 3 * (order + 1) : 0;
    std::vector<float> src(plane * planes, 1.f), dst(plane * planes), acc(plane * planes),
        fac(std::max<size_t>(plane * factorPlanes, 1), 0.5f);
    std::vector<double> floorMs;
    volatile float sink = 0.f;
    for (int i = 0; i < repeats + 3; ++i) {
        const Timer t;
        for (int s = 0; s < steps; ++s) {
            parallelFor(
                0, int64_t(planes),
                [&](int64_t b, int64_t e) {
                    for (int64_t p = b; p < e; ++p) {
                        const float* __restrict a = &src[size_t(p) * plane];
                        float* __restrict d = &dst[size_t(p) * plane];
                        float* __restrict c = &acc[size_t(p) * plane];
                        std::memcpy(d, a, plane * sizeof(float));
                        for (size_t k = 0; k < plane; ++k)
                            c[k] += a[k];
                    }
                },
                1);
            if (het) {
                float f = 0.f;
                for (size_t k = 0; k < fac.size(); k += 16)
                    f += fac[k];  // one read per line
                sink = sink + f;
            }
            std::swap(src, dst);
        }
        if (i >= 3)
            floorMs.push_back(t.elapsedMs());
    }
    (void)sink;

    // GL compute path: the same propagation on the GPU (injection and factors from the CPU).
    double glGpuMs = 0.0, glCpuMs = 0.0;
    if (gl) {
        std::string reason;
        if (!gpu::GlContext::isHeadlessAvailable(&reason))
            LUCENT_THROW(GpuError, "--gl: no headless OpenGL 4.5 context: ", reason);
        auto ctx = gpu::GlContext::createHeadless();
        SslpvGlPropagator prop(args.has("fp16") ? SslpvGlStorage::Float16
                                                : SslpvGlStorage::Float32);
        const int glRepeats = std::max(3, std::min(repeats, 10));  // llvmpipe is slow
        prop.propagate(solver);                                    // warm-up (shader JIT)
        std::vector<double> g, c;
        for (int i = 0; i < glRepeats; ++i) {
            prop.propagate(solver);
            g.push_back(prop.timings().propagateGpuMs);
            c.push_back(prop.timings().uploadCpuMs + prop.timings().propagateCpuMs +
                        prop.timings().readbackCpuMs);
        }
        glGpuMs = median(g);
        glCpuMs = median(c);
        prop.destroy();
        std::printf("%sGL %s (%s): propagation %.3f ms GPU timer, %.3f ms with upload + readback\n",
                    args.has("json") ? "# " : "", ctx->renderer().c_str(),
                    args.has("fp16") ? "fp16" : "fp32", glGpuMs, glCpuMs);
    }

    const double msSolve = median(solveMs);
    const double msSteps = median(stepsMs);
    const double msPerStep = msSteps / steps;
    const double floorPerStep = median(floorMs) / steps;
    const double paperMs = 1.67;  // GTX 580, 32³, 8 steps, heterogeneous (Table 1, Fig. 6)
    if (args.has("json")) {
        std::printf(
            "{\"benchmark\": \"sslpv\", \"grid\": %d, \"steps\": %d, \"sh_order\": %d, "
            "\"heterogeneous\": %s, \"dense\": %s, \"threads\": %d, \"repeats\": %d, "
            "\"ms_per_solve\": %.4f, "
            "\"cpu_ms_per_solve\": %.4f, "
            "\"ms_propagation\": %.4f, \"ms_per_step\": %.5f, \"floor_ms_per_step\": %.5f, "
            "\"ratio_to_floor\": %.3f, \"gl_gpu_ms\": %.4f, \"gl_total_ms\": %.4f, "
            "\"paper_ms_gtx580_32_8_het\": %.2f}\n",
            n, steps, order, het ? "true" : "false", args.has("dense") ? "true" : "false", threads,
            repeats, msSolve, cpuPerSolve, msSteps, msPerStep, floorPerStep,
            msPerStep / floorPerStep, glGpuMs, glCpuMs, paperMs);
    } else {
        std::printf(
            "SSLPV CPU propagation: %d^3 cells, %d steps, SH order %d, %s, %s, %d "
            "thread(s)\n",
            n, steps, order, het ? "heterogeneous" : "homogeneous",
            args.has("dense") ? "dense" : "empty slices skipped", threads);
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

}  // namespace

/// `lucent-cli render --method sslpv` (Command_render.cpp): the CPU SSLPV renderer.
ImageRgb renderSslpvMethod(const Scene& scene, bool subsurfaceOnly, const Args& args) {
    SslpvRenderOptions opt;
    opt.gridResolution = args.intOr("grid", 32, 4, 256);
    opt.solver.maxSteps = args.intOr("steps", 32, 0, 4096);
    opt.solver.order = args.intOr("sh", 1, 1, 2);
    opt.direct = !subsurfaceOnly;
    // Absorption-only attenuation by default: within −15 %…+22 % of diffusion on thick slabs
    // for α′ ≥ 0.5, where the paper's literal extinction is 5–50× too dark
    // (docs/methods/sslpv.md).
    const std::string att = args.valueOr("attenuation", "absorption");
    if (att == "extinction")
        opt.solver.attenuation = SslpvAttenuation::Extinction;
    else if (att == "absorption")
        opt.solver.attenuation = SslpvAttenuation::Absorption;
    else
        LUCENT_THROW(ValueError, "--attenuation: '", att, "' is not absorption or extinction");
    SslpvRenderTimings t;
    SslpvStats st;
    ImageRgb image = renderSslpv(scene, opt, &t, &st);
    std::fprintf(stderr,
                 "sslpv: %d steps, injected %.4g W (green), exitant %.4g W, remaining %.4g W\n"
                 "  rsm %.2f ms, resample %.2f ms, inject %.2f ms, propagate %.2f ms, "
                 "shade %.2f ms (CPU)\n",
                 st.stepsUsed, double(st.injected.y), double(st.exitant.y), double(st.remaining.y),
                 t.rsmMs, t.resampleMs, t.injectMs, t.propagateMs, t.shadeMs);
    return image;
}

extern const Command benchCommand;
const Command benchCommand{
    "bench", "time the SSLPV propagation against a bandwidth floor",
    "usage: lucent-cli bench sslpv [--grid N] [--steps K] [--sh 1|2] [--heterogeneous]\n"
    "                              [--dense] [--threads T] [--repeats R] [--gl [--fp16]]\n"
    "                              [--json]\n"
    "\n"
    "Times repeated SSLPV solves (per-cell factors + propagation) on an N^3 grid whose cells\n"
    "are all material (the paper's set-up, light injected on one face), after 3 warm-up\n"
    "solves, and prints medians next to a memory-bandwidth floor measured in the same run\n"
    "(streaming the same planes: copy + accumulate, per step).\n"
    "\n"
    "  --grid N          cells per axis, [4, 256] (default 32)\n"
    "  --steps K         propagation steps, [1, 4096] (default 8)\n"
    "  --sh 1|2          spherical-harmonics order: 4 or 9 coefficients (default 1)\n"
    "  --heterogeneous   random per-cell material (per-cell factor arrays)\n"
    "  --dense           compute every cell every step (no empty-slice skipping: the\n"
    "                    paper's dense GPU work)\n"
    "  --threads T       worker threads (default: all)\n"
    "  --repeats R       timed solves (default 50)\n"
    "  --gl              also time the GL 4.5 compute propagation (headless EGL context;\n"
    "                    GPU timer queries), fp32 grids\n"
    "  --fp16            with --gl: fp16 grids\n"
    "  --json            one JSON object: ms_per_solve, ms_propagation, ms_per_step,\n"
    "                    floor_ms_per_step, ratio_to_floor (gl_gpu_ms, gl_total_ms: 0 without "
    "--gl)\n",
    &runBench};

}  // namespace lucent::cli
