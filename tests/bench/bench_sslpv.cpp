// SPDX-License-Identifier: MIT
/// @file
/// @brief SSLPV propagation timings (Google Benchmark) on the scenes of `lucent-cli bench
/// sslpv` (SslpvBench.h, the same fixture), with the bandwidth floor measured in the same run:
/// counters ms_per_step, floor_ms_per_step, ratio_to_floor, active_bricks. Arguments: scene
/// (SslpvBenchScene), grid, steps, SH order, heterogeneous (0/1), dense (0/1). Paper anchor:
/// cube, 32³, 8 steps, heterogeneous, 1.67 ms (GTX 580).

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

}  // namespace

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
