// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Scoring translucency methods against the exact reference: method variants and their
/// quality levels (from the method registry), the reference cache (scene hash + reference
/// estimator version), the per-case metrics and the run over a list of cases.
///
///     std::vector<Variant> variants = parseVariants("direct,dirpole,sslpv:paper");
///     RunOptions opt;  opt.outDir = "build/evaluation";  opt.refSpp = 256;
///     for (const EvalCase& c : buildSuite("default")) {
///         CaseRun run = evaluateCase(c, variants, opt);
///         for (const Result& r : run.results) ...;   // r.metrics.blockRelL1(), r.costRatio
///     }
///
/// Metrics (lucent/bench/ErrorMetrics.h has the definitions): over the pixels the reference's
/// coverage layer marks as object, 4×4-pixel blocks, luminance (Rec. 709) and per channel:
/// block relative L1 and block relative RMSE with the reference's noise floor subtracted in
/// quadrature, the 95th-percentile block error and the mean ratio Σ test / Σ reference.
/// Cost: a method's wall time over the Direct render's of the same frame in the same run, and
/// the same ratio of process CPU times (steadier when other processes share the cores).

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Image.h>
#include <lucent/evaluation/Suite.h>
#include <lucent/methods/Method.h>
#include <lucent/planner/SceneFeatures.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace lucent::evaluation {

/// The goal of issue 14 for the best live method on every case.
inline constexpr double GOAL_BLOCK_REL_L1 = 0.10;
inline constexpr double GOAL_MEAN_RATIO_TOLERANCE = 0.05;

// ---------------------------------------------------------------------------------------------
// Variants

/// A method with its variant suffix ("sslpv:paper") and its quality levels, cheapest first.
struct Variant {
    std::string name;                            ///< as given: "sslpv:paper"
    std::string method;                          ///< registry name: "sslpv"
    methods::ParamPreset variant;                ///< the suffix's values and backend
    std::vector<methods::ParamPreset> settings;  ///< quality levels (MethodInfo::quality)
};

/// Parses "method[:suffix]". @throw ValueError naming the entry and what is known.
Variant parseVariant(const std::string& entry);
/// Parses a comma-separated list (spaces ignored). @throw ValueError for an empty list.
std::vector<Variant> parseVariants(const std::string& list);
/// The registry's default evaluation: every method's MethodInfo::evaluate variants.
std::string defaultVariants();
/// "direct, sslpv[:paper|:calibrated], ..." for messages and help.
std::string knownVariants();

// ---------------------------------------------------------------------------------------------
// Reference cache

/// FNV-1a 64 of everything that decides a reference image: every object's mesh and painted
/// volume (values, inside mask, grid, η), the lights, the environment, the camera and η.
uint64_t hashScene(const Scene& scene);

struct ReferenceSettings {
    int spp = 256;
    bool subsurfaceOnly = false;
    /// The path tracer's seed. Another seed gives an independent estimate of the same image:
    /// evaluating against it shows how far a measured error moves with the reference's noise.
    int seed = 1;
};

/// The samples per pixel a reference needs for its block rel. L1 noise floor to fall from
/// `pilotFloor` (measured on a `pilotSpp` render) to `targetFloor`. The floor is the reference's
/// Monte Carlo error, which falls as 1/√spp: pilotSpp·(pilotFloor/targetFloor)², rounded up to a
/// whole number of pilots, never below the pilot, at most `maxSpp` (when it is ≥ the pilot).
/// @throw ValueError for a non-positive spp or target, or a negative or non-finite floor.
int sppForNoiseFloor(int pilotSpp, double pilotFloor, double targetFloor, int maxSpp);

/// Runs slower than this factor times the fastest are left out of a render's steady time.
inline constexpr double STEADY_RUN_FACTOR = 1.5;

/// The steady time of a render from its timed runs (ms): the median of the runs within
/// STEADY_RUN_FACTOR × the fastest. Every run creates its own headless GL context, and on
/// Mesa llvmpipe some of those contexts compile shaders that the shader cache did not serve:
/// about 80 ms more, 3× the suite's 64×64 Direct render, in 1 to 5 of a case's 9 Direct runs
/// in every one of ten processes measured (resources/evaluation/README.md). Such delays only
/// ever add time, so the fastest run bounds the steady cost from above, and a run 1.5× slower
/// than it is not the steady cost (the same factor as the Direct brackets' warning). Where
/// every run is within the factor this is the plain median. @param dropped if given, the
/// number of runs left out.
/// @throw ValueError for no runs or a negative or non-finite time.
double steadyMedian(std::vector<double> runsMs, int* dropped = nullptr);

/// A case's reference with its noise floor.
struct CachedReference {
    ImageRgb mean, variance, coverage;
    std::vector<uint8_t> mask;  ///< coverage > 0.5: the compared pixels
    int spp = 0;
    double seconds = 0.0;  ///< render time (0 when loaded from the cache)
    bool cached = false;
    std::string path;  ///< the EXR (mean + "variance" + "coverage" layers)
    /// The reference against itself: the errors a method would get if it differed from the
    /// reference by the reference's Monte Carlo noise only (luminance; floors of ErrorReport).
    double blockRelL1Floor = 0.0;
    double blockRelRmseFloor = 0.0;
    double pixelRelRmseFloor = 0.0;
    double meanLuminance = 0.0;  ///< over the compared pixels
};

/// The reference of `scene`, from `dir` when DIR/<name>_ref_<W>x<H>_<spp>spp[_sss][_seedS].key
/// holds the same key (scene hash, size, spp, seed, boundary, REFERENCE_ESTIMATOR_VERSION,
/// subsurface-only), else rendered (dielectric boundary) and written there. The stem names the
/// seed only when it is not the default 1.
/// @throw IoError when the cache cannot be read or written; ValueError from the renderer.
CachedReference referenceFor(const Scene& scene, const std::string& name, const std::string& dir,
                             const ReferenceSettings& options);

// ---------------------------------------------------------------------------------------------
// Metrics

/// One render scored against a reference.
struct Metrics {
    bench::ErrorReport
        report;  ///< per channel R, G, B and luminance (index ErrorReport::LUMINANCE)

    static constexpr int LUM = bench::ErrorReport::LUMINANCE;
    /// Block relative L1 of channel c, reference noise removed in quadrature.
    [[nodiscard]] double blockRelL1(int c = LUM) const { return report.blocks[c].relL1Net; }
    [[nodiscard]] double blockRelRmse(int c = LUM) const { return report.blocks[c].relRmseNet; }
    [[nodiscard]] double meanRatio(int c = LUM) const { return report.channels[c].meanRatio; }
    [[nodiscard]] double p95(int c = LUM) const { return report.blocks[c].p95; }
    /// Within GOAL_BLOCK_REL_L1 and 1 ± GOAL_MEAN_RATIO_TOLERANCE on luminance.
    [[nodiscard]] bool meetsGoal() const;
};

/// Scores `test` against the reference over its mask.
/// @throw ValueError for a size mismatch or a non-finite pixel.
Metrics scoreImage(const ImageRgb& test, const CachedReference& reference);

/// Indices of the points on the Pareto front of (cost, error), both to be minimised: a point
/// is on it when no other point has cost ≤ and error ≤ with one of them <. Sorted by cost;
/// of exact duplicates only the first is kept.
std::vector<size_t> paretoFront(const std::vector<double>& cost, const std::vector<double>& error);

// ---------------------------------------------------------------------------------------------
// Running

/// `name` with ':', '/', ' ' and ',' replaced by '-' (output file names).
std::string fileSafe(std::string name);

/// One method setting on one case.
struct Result {
    std::string caseName;
    std::string group;
    std::string variant;    ///< "sslpv:paper"
    std::string setting;    ///< the quality level's name
    int quality = 0;        ///< index of the setting, cheapest first
    std::string backend;    ///< "gl" or "cpu"
    double msMedian = 0.0;  ///< wall, steadyMedian of the timed runs
    double msMin = 0.0;
    int runs = 0;
    double directMs = 0.0;   ///< the Direct render of the same frame, same run (steadyMedian)
    double costRatio = 0.0;  ///< msMedian / directMs
    /// Process CPU time (all threads, llvmpipe's included; steadyMedian), and its ratio to the
    /// Direct render's: unlike wall time, barely moved by other processes on a shared box.
    double cpuMsMedian = 0.0;
    double directCpuMs = 0.0;
    double cpuCostRatio = 0.0;
    Metrics metrics;
    double noiseFloor = 0.0;  ///< the reference's block rel. L1 floor (luminance)
    /// Block relative L1 (luminance, over the reference's mask) of this setting's image
    /// against the same variant's next finer setting: what refining buys on this case (the
    /// planner's level check, lucent/planner/LevelCheck.h). < 0 for the finest setting
    /// measured, or when the finer one was not rendered.
    double blockRelL1ToFiner = -1.0;
    std::optional<planner::SceneFeatures> features;  ///< of the case (empty if not analysable)
    std::string image;                               ///< EXR written (empty if none)
};

struct RunOptions {
    std::string outDir;  ///< references, images; must exist
    int refSpp = 256;
    /// The reference's seed (ReferenceSettings::seed); the `reference` method, scored as a
    /// method, runs with refSeed + 6 so that its error is the noise of two independent estimates.
    int refSeed = 1;
    /// When > 0, each case's reference is a stated-noise reference: a case whose refSpp render
    /// (the pilot) has a block rel. L1 floor above this is rendered again at the samples
    /// sppForNoiseFloor predicts, at most refMaxSpp (so a very noisy case stops short of it;
    /// the floor reached is what the case reports).
    double refFloor = 0.0;
    int refMaxSpp = 8192;
    int repeats = 3;  ///< timed runs per setting after one warm-up
    int levels = 3;   ///< at most this many quality settings per variant
    bool subsurfaceOnly = false;
    bool writeImages = true;     ///< an EXR and a PNG preview per render
    bool silenceMethods = true;  ///< the methods' stderr logs go to /dev/null while rendering
    methods::Log methodLog;      ///< the methods' notes (fallbacks); may be empty
    std::function<void(const std::string&)> progress;  ///< one line per step; may be empty
};

/// What a case's run produced.
struct CaseRun {
    CachedReference reference;
    double directMs = 0.0;     ///< wall, steadyMedian
    double directCpuMs = 0.0;  ///< process CPU time, steadyMedian
    std::optional<planner::SceneFeatures> features;
    std::vector<Result> results;
    std::vector<std::string> skipped;  ///< "case: variant (setting): why"
};

/// The reference (cached), the Direct render's time, then every variant at up to
/// options.levels settings: steady wall and CPU time (steadyMedian) of options.repeats renders
/// after a warm-up, and the metrics. A variant that throws is skipped (with the reason) at its
/// remaining settings.
CaseRun evaluateCase(const EvalCase& evalCase, const std::vector<Variant>& variants,
                     const RunOptions& options);

}  // namespace lucent::evaluation
