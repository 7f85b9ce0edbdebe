// SPDX-License-Identifier: MIT
/// @file
/// @brief SSLPV propagation timings (Google Benchmark) with a bandwidth floor measured in the
/// same run: counters ms_per_step, floor_ms_per_step, ratio_to_floor. Arguments: grid, steps,
/// SH order, heterogeneous (0/1). Paper anchor: 32³, 8 steps, heterogeneous, 1.67 ms (GTX 580).

#include <lucent/core/Random.h>
#include <lucent/core/Timer.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstring>
#include <vector>

using namespace lucent;

namespace {

CoarseMaterial material(int n, bool het) {
    CoarseMaterial m;
    m.spec.resolution = n;
    m.spec.voxelSize = 1.f;
    const size_t count = m.spec.voxelCount();
    m.insideFraction.assign(count, 1.f);
    Pcg32 rng(7);
    for (int c = 0; c < 3; ++c) {
        m.sigma_t[c].assign(count, 1.f);
        m.sigma_s[c].assign(count, 0.8f);
        m.g[c].assign(count, 0.2f);
        if (het)
            for (size_t k = 0; k < count; ++k) {
                m.sigma_t[c][k] = 0.5f + 1.5f * rng.uniform();
                m.sigma_s[c][k] = m.sigma_t[c][k] * rng.uniform();
                m.g[c][k] = 1.6f * rng.uniform() - 0.8f;
            }
    }
    return m;
}

/// Median ms of one "step" of pure streaming over the same planes (copy + accumulate).
double floorMsPerStep(int n, int order) {
    const size_t plane = size_t(n + 2) * (n + 2) * (n + 2) * 3 * shCount(order);
    std::vector<float> src(plane, 1.f), dst(plane), acc(plane);
    std::vector<double> t;
    for (int r = 0; r < 30; ++r) {
        const Timer timer;
        std::memcpy(dst.data(), src.data(), plane * sizeof(float));
        for (size_t k = 0; k < plane; ++k)
            acc[k] += src[k];
        benchmark::DoNotOptimize(acc.data());
        t.push_back(timer.elapsedMs());
    }
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
}

void BM_SslpvPropagate(benchmark::State& state) {
    const int n = int(state.range(0)), steps = int(state.range(1)), order = int(state.range(2));
    const bool het = state.range(3) != 0;
    // Dense (every cell every step, the paper's GPU work): no empty-slice skipping.
    SslpvSolver solver({.order = order,
                        .maxSteps = steps,
                        .skipAccumulateSteps = 0,
                        .removeExitant = false,
                        .skipEmptySlices = false});
    solver.setMaterial(material(n, het), 1.3f);
    std::vector<SslpvInjectionSample> texels;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            texels.push_back({Point3f(x + 0.5f, y + 0.5f, float(n)), Normal3f(0, 0, 1),
                              Vector3f(0, 0, -1), Rgb(1.f)});
    solver.setInjectionSamples(std::move(texels));
    solver.solve();
    double stepsMs = 0.0;
    for (auto _ : state) {
        solver.markMaterialDirty();
        solver.solve();
        stepsMs += solver.stats().stepsMs;
    }
    const double perStep = stepsMs / double(state.iterations()) / steps;
    const double floor = floorMsPerStep(n, order);
    state.counters["ms_per_step"] = perStep;
    state.counters["floor_ms_per_step"] = floor;
    state.counters["ratio_to_floor"] = perStep / floor;
}

}  // namespace

BENCHMARK(BM_SslpvPropagate)
    ->Args({32, 8, 1, 0})
    ->Args({32, 8, 1, 1})
    ->Args({32, 32, 1, 1})
    ->Args({32, 8, 2, 1})
    ->Args({64, 8, 1, 1})
    ->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
