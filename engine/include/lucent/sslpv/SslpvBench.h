// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The SSLPV propagation benchmark: its scenes, bandwidth floor and timed run, shared by
/// `lucent-cli bench sslpv` (which parses and prints) and tests/bench/bench_sslpv.cpp so both
/// time the same work (docs/benchmarks.md, SSLPV).
///
///     SslpvBenchSetup b = makeSslpvBenchSetup(SslpvBenchScene::Shell, 32, /*heterogeneous=*/true);
///     SslpvSolver solver({.maxSteps = 8, .removeExitant = b.sinks});
///     solver.setMaterial(b.material, b.eta);
///     solver.setInjectionSamples(b.texels);
///     double floorMs = sslpvBandwidthFloorMs(32, /*order=*/1, true, /*steps=*/8, /*repeats=*/20);

#include <lucent/sslpv/SslpvSolver.h>

#include <string>
#include <vector>

namespace lucent::sslpv {

/// Benchmark scenes on an N³ grid of 1 mm cells.
enum class SslpvBenchScene {
    Cube,    ///< the paper's set-up (§5): every cell material, no sinks, the top face lit
    Sphere,  ///< ball of radius 0.45·N with sinks, lit from above (a directional light)
    Shell,   ///< hollow ball, radii 0.38·N–0.45·N (≈ 2 cells at 32³), sinks, lit from above
    Spot,    ///< every cell material, no sinks, a 4 × 4-cell spot at the top face's centre
};

/// Parses "cube", "sphere", "shell" or "spot". @throw ValueError naming the option otherwise.
SslpvBenchScene parseSslpvBenchScene(const std::string& name);
/// The lower-case name parseSslpvBenchScene() accepts.
const char* sslpvBenchSceneName(SslpvBenchScene scene);

/// Material, injection texels and sink setting of one benchmark scene.
struct SslpvBenchSetup {
    CoarseMaterial material;
    std::vector<SslpvInjectionSample> texels;  ///< unit flux per texel (W), one per lit cell
    bool sinks = false;                        ///< SslpvOptions::removeExitant for the scene
    float eta = 1.3f;
};

/// @param n cells per axis, [4, 1022]. @param heterogeneous random per-cell σt ∈ [0.5, 2] mm⁻¹,
/// σs′ = u·σt, g ∈ [−0.8, 0.8] (seeded Pcg32, so the per-cell factor arrays are read every
/// step); otherwise σt = 1, σs′ = 0.8 mm⁻¹, g = 0.2 everywhere.
/// @throw ValueError for n out of range.
SslpvBenchSetup makeSslpvBenchSetup(SslpvBenchScene scene, int n, bool heterogeneous);

/// Median wall time (ms) of `steps` memory-streaming steps over the same bytes one dense
/// propagation step touches at least: per step, copy the 3·(order+1)² source planes of
/// (N+2)³ floats into destination planes and add them into accumulation planes (parallelFor
/// over planes, the caller's thread limit applies), plus one read per cache line of the
/// 3·(order+1) factor planes when heterogeneous. Median over `repeats` after 3 warm-ups.
/// @throw ValueError for n, order, steps or repeats out of range.
double sslpvBandwidthFloorMs(int n, int order, bool heterogeneous, int steps, int repeats);

/// One benchmark run: what `lucent-cli bench sslpv` times.
struct SslpvBenchRun {
    SslpvBenchScene scene = SslpvBenchScene::Cube;
    int gridCells = 32, steps = 8, order = 1;
    int repeats = 50;  ///< timed solves after 3 warm-ups
    bool heterogeneous = false;
    bool dense = false;  ///< every cell every step (SslpvOptions::skipEmptySlices off)
    bool gl = false;     ///< also the GL compute propagation (needs a headless GL 4.5 context)
    bool fp16 = false;   ///< the GL grids in half floats
};

/// What one run measured; times in ms, medians over the repeats (medianMs).
struct SslpvBenchResult {
    double solveMs = 0.0;       ///< wall, one solve (factors + propagation)
    double cpuSolveMs = 0.0;    ///< process CPU time per solve (all threads)
    double stepsMs = 0.0;       ///< the propagation steps of one solve (SslpvStats::stepsMs)
    double floorStepMs = 0.0;   ///< sslpvBandwidthFloorMs / steps, same run, same threads
    int brickCount = 0;         ///< bricks of the grid
    double activeBricks = 0.0;  ///< mean active bricks per step
    double cellsPerStep = 0.0;  ///< cells computed per step
    /// GL (run.gl only): propagation by the GPU timer, wall per propagate, input upload and
    /// read-back when asked; the context's GL_RENDERER.
    double glGpuMs = 0.0, glWallMs = 0.0, glUploadMs = 0.0, glReadbackMs = 0.0;
    std::string glRenderer;
};

/// Times repeated re-propagations of one scene (what a paint stroke triggers: markMaterialDirty
/// + solve), after 3 warm-ups, under the caller's ThreadLimit, and the bandwidth floor in the
/// same run. @throw ValueError for arguments out of range; GpuError when run.gl and no headless
/// context can be made.
SslpvBenchResult runSslpvBench(const SslpvBenchRun& run);

}  // namespace lucent::sslpv
