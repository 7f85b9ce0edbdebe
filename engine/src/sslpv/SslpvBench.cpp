// SPDX-License-Identifier: MIT
/// @file
/// @brief Benchmark scenes and bandwidth floor of the SSLPV propagation (SslpvBench.h).

#include <lucent/sslpv/SslpvBench.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Random.h>
#include <lucent/core/Timer.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/sslpv/SslpvGl.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace lucent::sslpv {

SslpvBenchScene parseSslpvBenchScene(const std::string& name) {
    for (SslpvBenchScene s : {SslpvBenchScene::Cube, SslpvBenchScene::Sphere,
                              SslpvBenchScene::Shell, SslpvBenchScene::Spot})
        if (name == sslpvBenchSceneName(s))
            return s;
    LUCENT_THROW(ValueError, "--scene: '", name, "' is not cube, sphere, shell or spot");
}

const char* sslpvBenchSceneName(SslpvBenchScene scene) {
    switch (scene) {
        case SslpvBenchScene::Cube:
            return "cube";
        case SslpvBenchScene::Sphere:
            return "sphere";
        case SslpvBenchScene::Shell:
            return "shell";
        case SslpvBenchScene::Spot:
            return "spot";
    }
    return "?";
}

SslpvBenchSetup makeSslpvBenchSetup(SslpvBenchScene scene, int n, bool heterogeneous) {
    LUCENT_CHECK(n >= 4 && n <= 1022, "SSLPV bench: grid ", n, " outside [4, 1022]");
    SslpvBenchSetup b;
    CoarseMaterial& m = b.material;
    m.spec.resolution = n;
    m.spec.voxelSize = 1.f;
    m.spec.origin = Point3f(0.f);
    const size_t count = m.spec.voxelCount();
    const bool ball = scene == SslpvBenchScene::Sphere || scene == SslpvBenchScene::Shell;
    const float c = 0.5f * float(n), outer = 0.45f * float(n);
    const float inner = scene == SslpvBenchScene::Shell ? 0.38f * float(n) : -1.f;
    m.insideFraction.assign(count, ball ? 0.f : 1.f);
    if (ball)
        for (int z = 0; z < n; ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const float r = glm::length(m.spec.cellCenter({x, y, z}) - Point3f(c));
                    if (r <= outer && r >= inner)
                        m.insideFraction[m.spec.linearIndex({x, y, z})] = 1.f;
                }
    Pcg32 rng(1234);
    for (int ch = 0; ch < 3; ++ch) {
        m.sigma_t[ch].assign(count, 1.f);
        m.sigma_s[ch].assign(count, 0.8f);
        m.g[ch].assign(count, 0.2f);
        if (heterogeneous)
            for (size_t k = 0; k < count; ++k) {
                m.sigma_t[ch][k] = 0.5f + 1.5f * rng.uniform();
                m.sigma_s[ch][k] = m.sigma_t[ch][k] * rng.uniform();
                m.g[ch][k] = 1.6f * rng.uniform() - 0.8f;
            }
    }
    m.homogeneous = !heterogeneous;
    b.sinks = ball;

    // One unit-flux texel per lit column (x, y) of cells.
    switch (scene) {
        case SslpvBenchScene::Cube:
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x)
                    b.texels.push_back({Point3f(x + 0.5f, y + 0.5f, float(n)), Normal3f(0, 0, 1),
                                        glm::normalize(Vector3f(0.3f, 0.1f, -1.f)), Rgb(1.f)});
            break;
        case SslpvBenchScene::Spot:
            for (int y = n / 2 - 2; y < n / 2 + 2; ++y)
                for (int x = n / 2 - 2; x < n / 2 + 2; ++x)
                    b.texels.push_back({Point3f(x + 0.5f, y + 0.5f, float(n)), Normal3f(0, 0, 1),
                                        Vector3f(0, 0, -1), Rgb(1.f)});
            break;
        case SslpvBenchScene::Sphere:
        case SslpvBenchScene::Shell:
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const float dx = x + 0.5f - c, dy = y + 0.5f - c;
                    const float r2 = dx * dx + dy * dy;
                    if (r2 >= outer * outer)
                        continue;
                    const Vector3f d(dx, dy, std::sqrt(outer * outer - r2));
                    b.texels.push_back(
                        {Point3f(c) + d, Normal3f(d / outer), Vector3f(0, 0, -1), Rgb(1.f)});
                }
            break;
    }
    return b;
}

double sslpvBandwidthFloorMs(int n, int order, bool heterogeneous, int steps, int repeats) {
    LUCENT_CHECK(n >= 1 && n <= 1022 && (order == 1 || order == 2) && steps >= 1 && repeats >= 1,
                 "SSLPV bandwidth floor: grid ", n, ", order ", order, ", steps ", steps,
                 ", repeats ", repeats, " out of range");
    const size_t plane = size_t(n + 2) * (n + 2) * (n + 2);
    const size_t planes = size_t(3) * shCount(order);
    const size_t factorPlanes = heterogeneous ? size_t(3) * (order + 1) : 0;
    std::vector<float> src(plane * planes, 1.f), dst(plane * planes), acc(plane * planes),
        fac(std::max<size_t>(plane * factorPlanes, 1), 0.5f);
    std::vector<double> ms;
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
                /*grain=*/1);
            if (heterogeneous) {
                float f = 0.f;
                for (size_t k = 0; k < fac.size(); k += 16)
                    f += fac[k];  // one read per 64-byte line
                sink = sink + f;
            }
            std::swap(src, dst);
        }
        if (i >= 3)
            ms.push_back(t.elapsedMs());
    }
    (void)sink;
    std::sort(ms.begin(), ms.end());
    return ms[ms.size() / 2];
}

SslpvBenchResult runSslpvBench(const SslpvBenchRun& run) {
    LUCENT_CHECK(run.repeats >= 1 && run.repeats <= 100000, "SSLPV bench: repeats ", run.repeats,
                 " is outside [1, 100000]");
    LUCENT_CHECK(run.steps >= 1, "SSLPV bench: steps must be >= 1 (got ", run.steps, ")");
    SslpvBenchSetup setup = makeSslpvBenchSetup(run.scene, run.gridCells, run.heterogeneous);
    SslpvSolver solver({.order = run.order,
                        .maxSteps = run.steps,
                        .skipAccumulateSteps = 0,
                        .removeExitant = setup.sinks,
                        .skipEmptySlices = !run.dense});
    solver.setMaterial(setup.material, setup.eta);
    solver.setInjectionSamples(std::move(setup.texels));

    // Warm-up, then repeated re-propagations (what a paint stroke triggers).
    for (int i = 0; i < 3; ++i) {
        solver.markMaterialDirty();
        solver.solve();
    }
    std::vector<double> solveMs, stepsMs;
    const double cpu0 = processCpuMs();
    for (int i = 0; i < run.repeats; ++i) {
        solver.markMaterialDirty();
        const Timer t;
        solver.solve();
        solveMs.push_back(t.elapsedMs());
        stepsMs.push_back(solver.stats().stepsMs);
    }
    SslpvBenchResult r;
    r.cpuSolveMs = (processCpuMs() - cpu0) / run.repeats;
    r.solveMs = medianMs(solveMs);
    r.stepsMs = medianMs(stepsMs);
    // Bandwidth floor, same run, same threads: the least traffic one dense step can have
    // without the stencil (stream the source planes into the destination and add them into the
    // accumulation planes, plus the factor planes when heterogeneous).
    r.floorStepMs =
        sslpvBandwidthFloorMs(run.gridCells, run.order, run.heterogeneous, run.steps, run.repeats) /
        run.steps;
    const SslpvStats& st = solver.stats();
    r.brickCount = st.brickCount;
    for (int a : st.activeBricksPerStep)
        r.activeBricks += a;
    r.activeBricks /= double(std::max<size_t>(st.activeBricksPerStep.size(), 1));
    r.cellsPerStep = double(st.cellsComputed) / std::max(st.stepsUsed, 1);

    if (run.gl) {  // the same propagation on the GPU (injection and factors from the CPU)
        std::string reason;
        if (!gpu::GlContext::isHeadlessAvailable(&reason))
            LUCENT_THROW(GpuError, "SSLPV bench --gl: no headless OpenGL 4.5 context: ", reason);
        const auto ctx = gpu::GlContext::createHeadless();
        SslpvGlPropagator prop(run.fp16 ? SslpvGlStorage::Float16 : SslpvGlStorage::Float32);
        const int glRepeats = std::max(3, std::min(run.repeats, 10));  // llvmpipe is slow
        prop.propagate(solver);                                        // warm-up (shader JIT)
        // Steady state: persistent buffers, nothing changed to upload, no read-back; then the
        // read-back a CPU consumer would add, timed separately.
        std::vector<double> gpuMs, wallMs, uploadMs, readbackMs;
        for (int i = 0; i < glRepeats; ++i) {
            const Timer wall;
            prop.propagate(solver);
            wallMs.push_back(wall.elapsedMs());
            gpuMs.push_back(prop.timings().propagateGpuMs);
            uploadMs.push_back(prop.timings().uploadCpuMs);
            (void)prop.accumulation();
            readbackMs.push_back(prop.timings().readbackCpuMs);
        }
        r.glGpuMs = medianMs(gpuMs);
        r.glWallMs = medianMs(wallMs);
        r.glUploadMs = medianMs(uploadMs);
        r.glReadbackMs = medianMs(readbackMs);
        r.glRenderer = ctx->renderer();
        prop.destroy();
    }
    return r;
}

}  // namespace lucent::sslpv
