// SPDX-License-Identifier: MIT
/// @file
/// @brief SSLPV propagation timings (Google Benchmark) on the scenes of `lucent-cli bench
/// sslpv` (SslpvBench.h, the same fixture), with the bandwidth floor measured in the same run:
/// counters ms_per_step, floor_ms_per_step, ratio_to_floor, active_bricks. Arguments: scene
/// (SslpvBenchScene), grid, steps, SH order, heterogeneous (0/1), dense (0/1). Paper anchor:
/// cube, 32³, 8 steps, heterogeneous, 1.67 ms (GTX 580).

#include <lucent/sslpv/GridDiffusion.h>
#include <lucent/sslpv/SslpvBench.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <benchmark/benchmark.h>

#include <string>

using namespace lucent;
using namespace lucent::sslpv;

namespace {

void BM_SslpvPropagate(benchmark::State& state) {
    const auto scene = SslpvBenchScene(state.range(0));
    const int n = int(state.range(1)), steps = int(state.range(2)), order = int(state.range(3));
    const bool het = state.range(4) != 0, dense = state.range(5) != 0;
    SslpvBenchSetup setup = makeSslpvBenchSetup(scene, n, het);
    SslpvSolver solver({.order = order,
                        .maxSteps = steps,
                        .skipAccumulateSteps = 0,
                        .removeExitant = setup.sinks,
                        .skipEmptySlices = !dense});
    solver.setMaterial(setup.material, setup.eta);
    solver.setInjectionSamples(std::move(setup.texels));
    solver.solve();
    double stepsMs = 0.0;
    for (auto _ : state) {
        solver.markMaterialDirty();
        solver.solve();
        stepsMs += solver.stats().stepsMs;
    }
    const double perStep = stepsMs / double(state.iterations()) / steps;
    const double floor = sslpvBandwidthFloorMs(n, order, het, steps, /*repeats=*/20) / steps;
    double active = 0.0;
    for (int a : solver.stats().activeBricksPerStep)
        active += a;
    state.SetLabel(std::string(sslpvBenchSceneName(scene)) + (dense ? " dense" : " active"));
    state.counters["ms_per_step"] = perStep;
    state.counters["floor_ms_per_step"] = floor;
    state.counters["ratio_to_floor"] = perStep / floor;
    state.counters["active_bricks"] = active / steps;
    state.counters["bricks"] = solver.stats().brickCount;
}

/// Mode diffusion's solve of a stroke (the material marked dirty, the shape kept: a warm start)
/// with the surface cells scaled to the half-space (0) or to the exact slab of their part (1,
/// SslpvOptions::diffusionSlabTotal): what the slab costs a stroke. The sphere at 64³.
void BM_DiffusionStrokeSolve(benchmark::State& state) {
    SslpvBenchSetup setup = makeSslpvBenchSetup(SslpvBenchScene::Sphere, 64, true);
    SslpvOptions o;
    o.mode = SslpvMode::Diffusion;
    o.diffusionSlabTotal = state.range(0) != 0;
    SslpvSolver solver(o);
    solver.setMaterial(setup.material, setup.eta);
    solver.setInjectionSamples(std::move(setup.texels));
    solver.solve();
    for (auto _ : state) {
        solver.markMaterialDirty();
        solver.solve();
    }
    state.SetLabel(state.range(0) ? "slab" : "half-space");
}

/// The chord march of a new shape (GridDiffusion::chordLength's first call after setMaterial
/// changed the inside fractions), the sphere at 64³, and the slab table's one-time build per η.
void BM_DiffusionChordMarch(benchmark::State& state) {
    SslpvBenchSetup setup = makeSslpvBenchSetup(SslpvBenchScene::Sphere, 64, true);
    CoarseMaterial& m = setup.material;
    size_t probe = 0;
    GridDiffusion d;
    d.setMaterial(m, setup.eta);
    while (!d.isBoundary(probe))
        ++probe;
    for (auto _ : state) {
        state.PauseTiming();
        m.insideFraction[0] = m.insideFraction[0] > 0.f ? 0.f : 0.1f;  // a new shape
        d.setMaterial(m, setup.eta);
        state.ResumeTiming();
        benchmark::DoNotOptimize(d.chordLength(probe));
    }
}

void BM_ExactSlabRatioTable(benchmark::State& state) {
    for (auto _ : state)
        benchmark::DoNotOptimize(ExactSlabRatio(1.3));
}

}  // namespace

BENCHMARK(BM_DiffusionStrokeSolve)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DiffusionChordMarch)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ExactSlabRatioTable)->Unit(benchmark::kMillisecond)->Iterations(3);

BENCHMARK(BM_SslpvPropagate)
    ->ArgsProduct({{int(SslpvBenchScene::Cube), int(SslpvBenchScene::Sphere),
                    int(SslpvBenchScene::Shell), int(SslpvBenchScene::Spot)},
                   {32},
                   {8},
                   {1},
                   {1},
                   {0, 1}})
    ->Args({int(SslpvBenchScene::Cube), 32, 32, 1, 1, 0})
    ->Args({int(SslpvBenchScene::Cube), 32, 8, 2, 1, 0})
    ->Args({int(SslpvBenchScene::Sphere), 64, 8, 1, 1, 0})
    ->Args({int(SslpvBenchScene::Sphere), 64, 8, 1, 1, 1})
    ->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
