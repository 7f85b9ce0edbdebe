// SPDX-License-Identifier: MIT
// The evaluation module: per-case metrics against hand-computed values, the Pareto front, the
// scene hash and reference cache, the suite's cases and the report files.

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>
#include <lucent/evaluation/Evaluate.h>
#include <lucent/evaluation/Report.h>
#include <lucent/evaluation/Suite.h>
#include <lucent/material/Brush.h>
#include <lucent/methods/RenderImage.h>

#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <filesystem>
#include <set>
#include <sstream>

namespace lucent::evaluation {
namespace {

namespace fs = std::filesystem;

/// Rec. 709 luminance weights (ErrorMetrics.h).
constexpr double WR = 0.2126, WG = 0.7152, WB = 0.0722;

/// An 8×4 reference of two 4×4 blocks, grey 1 (left) and grey 3 (right), every pixel covered,
/// with per-pixel variance `variance` in every channel.
CachedReference twoBlockReference(float variance) {
    CachedReference ref;
    ref.mean = ImageRgb(8, 4);
    ref.variance = ImageRgb(8, 4);
    ref.coverage = ImageRgb(8, 4);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 8; ++x) {
            ref.mean.at(x, y) = Rgb(x < 4 ? 1.f : 3.f);
            ref.variance.at(x, y) = Rgb(variance);
            ref.coverage.at(x, y) = Rgb(1.f);
        }
    ref.mask = bench::maskFromImage(ref.coverage);
    return ref;
}

TEST(EvaluationMetrics, LuminanceAndChannelsByHand) {
    // Test: the left block's red channel 1.2 instead of 1, everything else exact.
    const CachedReference ref = twoBlockReference(0.f);
    ImageRgb test = ref.mean;
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x)
            test.at(x, y) = Rgb(1.2f, 1.f, 1.f);
    const Metrics m = scoreImage(test, ref);
    // Red: block errors 0.2 and 0 over blocks of 16 pixels, Σ n b̄ = 16·1 + 16·3 = 64.
    EXPECT_NEAR(m.blockRelL1(0), 16 * 0.2 / 64.0, 1e-6);
    EXPECT_NEAR(m.blockRelRmse(0), std::sqrt(16 * 0.04 / 32.0) / 2.0, 1e-6);
    EXPECT_NEAR(m.meanRatio(0), (16 * 1.2 + 16 * 3.0) / 64.0, 1e-6);
    EXPECT_NEAR(m.blockRelL1(1), 0.0, 1e-12);  // green and blue exact
    EXPECT_NEAR(m.blockRelL1(2), 0.0, 1e-12);
    EXPECT_NEAR(m.meanRatio(2), 1.0, 1e-12);
    // Luminance: the left block is off by WR·0.2.
    EXPECT_NEAR(m.blockRelL1(), 16 * WR * 0.2 / 64.0, 1e-6);
    EXPECT_NEAR(m.meanRatio(), (16 * (1.0 + WR * 0.2) + 16 * 3.0) / 64.0, 1e-6);
    // Nearest-rank 95th percentile of the two block errors (WR·0.2 / 1 and 0): the larger.
    EXPECT_NEAR(m.p95(), WR * 0.2, 1e-6);
    // 0.011 block rel. L1 but mean ratio 1.011: inside the goal; 1.2× everywhere is not.
    EXPECT_TRUE(m.meetsGoal());
    ImageRgb bright = ref.mean;
    for (Rgb& p : bright.pixels())
        p *= 1.2f;
    const Metrics b = scoreImage(bright, ref);
    EXPECT_NEAR(b.blockRelL1(), 0.2, 1e-6);
    EXPECT_NEAR(b.meanRatio(), 1.2, 1e-6);
    EXPECT_FALSE(b.meetsGoal());
}

TEST(EvaluationMetrics, ReferenceNoiseIsRemovedInQuadrature) {
    // Per-pixel variance v in every channel: the luminance variance is (WR² + WG² + WB²)·v and
    // a block mean's is that / 16. Block rel. L1 floor = Σ n √(2/π) σ / Σ n b̄ = 32·√(2/π)σ/64.
    const float v = 0.09f;
    const CachedReference ref = twoBlockReference(v);
    ImageRgb test = ref.mean;
    for (Rgb& p : test.pixels())
        p *= 1.1f;  // raw block rel. L1 0.1
    const Metrics m = scoreImage(test, ref);
    const double sigma = std::sqrt((WR * WR + WG * WG + WB * WB) * v / 16.0);
    const double floorL1 = 32.0 * std::sqrt(2.0 / M_PI) * sigma / 64.0;
    EXPECT_NEAR(m.report.blocks[Metrics::LUM].relL1, 0.1, 1e-6);
    EXPECT_NEAR(m.report.blocks[Metrics::LUM].relL1Floor, floorL1, 1e-6);
    EXPECT_NEAR(m.blockRelL1(), std::sqrt(0.01 - floorL1 * floorL1), 1e-6);
    // RMSE: raw √(16·0.01 + 16·0.09)/32)/2, floor √(32 σ² / 32) / 2.
    const double rawRmse = std::sqrt((16 * 0.01 + 16 * 0.09) / 32.0) / 2.0;
    const double floorRmse = sigma / 2.0;
    EXPECT_NEAR(m.blockRelRmse(), std::sqrt(rawRmse * rawRmse - floorRmse * floorRmse), 1e-6);
}

TEST(EvaluationMetrics, ParetoFront) {
    // Sorted by cost: 0 (1, .5), 1 (2, .3), 4 (2, .3: a duplicate of 1), 2 (3, .4: dominated
    // by 1), 3 (4, .1).
    EXPECT_EQ(paretoFront({1, 2, 3, 4, 2}, {0.5, 0.3, 0.4, 0.1, 0.3}),
              (std::vector<size_t>{0, 1, 3}));
    // Equal cost: only the smaller error; a costlier point must be strictly better.
    EXPECT_EQ(paretoFront({5, 5, 6}, {0.2, 0.1, 0.1}), (std::vector<size_t>{1}));
    EXPECT_TRUE(paretoFront({}, {}).empty());
    EXPECT_THROW(paretoFront({1}, {}), ValueError);
}

TEST(EvaluationSuite, DefaultSuiteCoversTheIssue) {
    // The painted bunny needs the shared test meshes beside the checkout (not in the
    // repository); CI has them.
    SuiteOptions withMeshes;
    if (!std::filesystem::exists(sharedMeshesDir(withMeshes) + "/bunny_closed_75k.ply"))
        GTEST_SKIP() << "the shared test meshes are not at " << sharedMeshesDir(withMeshes);
    const std::vector<EvalCase> cases = buildSuite("default");
    std::set<std::string> names, groups;
    for (const EvalCase& c : cases) {
        EXPECT_TRUE(names.insert(c.name).second) << "duplicate case " << c.name;
        groups.insert(c.group);
        ASSERT_FALSE(c.scene.objects.empty()) << c.name;
        ASSERT_TRUE(c.scene.objects.front().material) << c.name;
        EXPECT_FALSE(c.scene.lights.empty()) << c.name;
        EXPECT_EQ(c.scene.camera.width, 64) << c.name;
        EXPECT_EQ(fileSafe(c.name), c.name) << "case names are file names";
        const planner::SceneFeatures f = planner::analyzeScene(c.scene);
        EXPECT_GT(f.insideVoxels, 0) << c.name;
        EXPECT_GT(f.pixelsCovered, 100.0) << c.name << ": the object should fill the frame";
        // Painted cases are heterogeneous, the others uniform (planner's own thresholds).
        const bool painted = c.group == "heterogeneous";
        EXPECT_EQ(!c.scene.objects.front().material->isHomogeneous(), painted) << c.name;
        // The back-lit cases are there for the planner's back-lit term: they must read as
        // back-lit to it (classify's threshold).
        if (c.name.rfind("backlit-", 0) == 0) {
            EXPECT_GT(f.backLitFraction, 0.5) << c.name;
        }
    }
    EXPECT_EQ(groups, (std::set<std::string>{"homogeneous", "heterogeneous", "shape", "lights",
                                             "deforming"}));
    for (const char* name :
         {"sphere-marble-eta1.3", "sphere-skin1-eta1", "sphere-jade-eta1.3",
          "sphere-wholemilk-eta1.3", "sphere-skin1-eta1.3-g0.8", "veins-marble", "layer-over-core",
          "g-layer-skin1", "bunny-painted", "backlit-thin-thick", "lights-spot",
          "lights-directional", "lights-two", "deformed-torus", "backlit-slab-skin1-eta1.3",
          "backlit-sphere-jade-eta1.3", "backlit-thin-torus-marble-eta1.3",
          "backlit-painted-slab-jade"})
        EXPECT_TRUE(names.count(name)) << name;
    EXPECT_THROW(buildSuite("nightly"), ValueError);
    EXPECT_EQ(filterCases(cases, {"lights-"}).size(), 3u);
    EXPECT_EQ(filterCases(cases, {"backlit-"}).size(), 5u);  // with backlit-thin-thick
    EXPECT_THROW(filterCases(cases, {"no-such-case"}), ValueError);
}

TEST(EvaluationSuite, WithoutTheSharedMeshesTheBunnyIsLeftOutWithANote) {
    SuiteOptions o;
    o.sharedMeshesDir = "/nonexistent/shared/meshes";
    std::vector<std::string> notes;
    o.log = [&](const std::string& m) { notes.push_back(m); };
    const std::vector<EvalCase> cases = buildSuite("default", o);
    EXPECT_TRUE(std::none_of(cases.begin(), cases.end(),
                             [](const EvalCase& c) { return c.name == "bunny-painted"; }));
    ASSERT_EQ(notes.size(), 1u);
    EXPECT_NE(notes[0].find("bunny-painted left out"), std::string::npos) << notes[0];
    EXPECT_NE(notes[0].find("LUCENT_SHARED_MESHES"), std::string::npos) << notes[0];
}

TEST(EvaluationReference, SceneHashSeesEveryInput) {
    const std::vector<EvalCase> smoke = buildSuite("smoke");
    const Scene& s = smoke.front().scene;
    const uint64_t h = hashScene(s);
    EXPECT_EQ(hashScene(s), h);
    Scene moved = s;
    moved.lights.front().position.x += 1.f;
    EXPECT_NE(hashScene(moved), h);
    Scene eta = s;
    eta.eta = 1.f;
    EXPECT_NE(hashScene(eta), h);
    Scene painted = s;  // a deep copy of the volume, then one stamp
    painted.objects.front().material =
        std::make_shared<MaterialVolume>(*s.objects.front().material);
    BrushSettings brush;
    brush.radius = 2.f;
    brush.value = MaterialSample{Rgb(2.f), Rgb(1.f), Rgb(0.f)};
    ASSERT_GT(stamp(*painted.objects.front().material, brush, Point3f(0.f)), 0u);
    EXPECT_NE(hashScene(painted), h);
    EXPECT_EQ(hashScene(s), h) << "the original volume is unchanged";
}

/// LUCENT_TEST_EVAL_DIR/name, emptied.
fs::path emptyTestDir(const char* name) {
    const fs::path dir = fs::path(LUCENT_TEST_EVAL_DIR) / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

/// The smoke suite's first case at size × size pixels.
EvalCase smokeCase(int size) {
    SuiteOptions o;
    o.width = size;
    o.height = size;
    return buildSuite("smoke", o).front();
}

TEST(EvaluationReference, CacheIsReusedOnlyForTheSameScene) {
    const fs::path dir = emptyTestDir("cache");
    const Scene scene = smokeCase(8).scene;
    const ReferenceSettings settings{4, false};
    const CachedReference first = referenceFor(scene, "c", dir.string(), settings);
    EXPECT_FALSE(first.cached);
    EXPECT_GT(first.blockRelL1Floor, 0.0) << "4 spp leave noise";
    const CachedReference again = referenceFor(scene, "c", dir.string(), settings);
    EXPECT_TRUE(again.cached);
    EXPECT_EQ(again.mean.pixels(), first.mean.pixels());
    EXPECT_DOUBLE_EQ(again.blockRelL1Floor, first.blockRelL1Floor);
    Scene other = scene;
    other.eta = 1.f;
    EXPECT_FALSE(referenceFor(other, "c", dir.string(), settings).cached);
}

TEST(EvaluationReference, AnotherSeedIsAnIndependentEstimateCachedBesideTheFirst) {
    // `evaluate --ref-seed`: how far measured errors move with the reference's own noise.
    const fs::path dir = emptyTestDir("cache-seed");
    const Scene scene = smokeCase(8).scene;
    const CachedReference one = referenceFor(scene, "c", dir.string(), {4, false});
    const CachedReference two = referenceFor(scene, "c", dir.string(), {4, false, 2});
    EXPECT_FALSE(two.cached) << "the seed is part of the cache key";
    EXPECT_NE(two.path, one.path);
    EXPECT_NE(two.path.find("_seed2"), std::string::npos) << two.path;
    EXPECT_NE(two.mean.pixels(), one.mean.pixels()) << "another seed, other samples";
    // Both estimate the same image: they differ by about their noise, not by more.
    const bench::ErrorReport d =
        bench::compareImages(two.mean, one.mean, &one.variance, &two.variance, &one.mask);
    const auto& lum = d.blocks[bench::ErrorReport::LUMINANCE];
    EXPECT_LT(lum.relL1, 3.0 * lum.relL1Floor) << lum.relL1 << " vs floor " << lum.relL1Floor;
    // Each is reused from its own file; the default seed's name is unchanged.
    EXPECT_TRUE(referenceFor(scene, "c", dir.string(), {4, false}).cached);
    EXPECT_TRUE(referenceFor(scene, "c", dir.string(), {4, false, 2}).cached);
    EXPECT_EQ(fs::path(one.path).filename().string(), "c_ref_8x8_4spp.exr");
}

/// A quick run into a fresh test folder: 4-spp reference, one timed repeat, no images.
RunOptions quickRun(const char* dirName, int levels) {
    RunOptions run;
    run.outDir = emptyTestDir(dirName).string();
    run.refSpp = 4;
    run.repeats = 1;
    run.levels = levels;
    run.writeImages = false;
    return run;
}

TEST(EvaluationRun, AStatedNoiseFloorRendersTheReferenceTheSamplesItNeeds) {
    // `evaluate --ref-floor`: the --ref-spp render is the pilot; a floor half the pilot's takes
    // four times its samples and reads about half of it (the floor falls as 1/√spp).
    const EvalCase c = smokeCase(16);
    RunOptions run = quickRun("ref-floor", 1);
    run.refSpp = 8;
    const CaseRun pilot = evaluateCase(c, {}, run);
    ASSERT_EQ(pilot.reference.spp, 8);
    const double floor8 = pilot.reference.blockRelL1Floor;
    ASSERT_GT(floor8, 0.0);
    run.refFloor = floor8 / 2;
    run.refMaxSpp = 1024;
    const CaseRun sharp = evaluateCase(c, {}, run);
    EXPECT_EQ(sharp.reference.spp, 32);
    EXPECT_FALSE(sharp.reference.cached) << "its own render, cached under its own spp";
    EXPECT_GT(sharp.reference.blockRelL1Floor, 0.3 * floor8);
    EXPECT_LT(sharp.reference.blockRelL1Floor, 0.7 * floor8);
    // The cap wins over the floor; a floor the pilot already meets keeps the pilot.
    run.refFloor = floor8 / 100;
    run.refMaxSpp = 16;
    EXPECT_EQ(evaluateCase(c, {}, run).reference.spp, 16);
    run.refFloor = 2 * floor8;
    const CaseRun kept = evaluateCase(c, {}, run);
    EXPECT_EQ(kept.reference.spp, 8);
    EXPECT_TRUE(kept.reference.cached);
}

TEST(EvaluationRun, EachSettingIsComparedWithTheNextFinerOne) {
    // What the planner's level check replays (planner/LevelCheck.h): a setting's image
    // against the same variant's next finer one, the block metric over the reference's mask.
    const EvalCase c = smokeCase(16);
    const RunOptions run = quickRun("to-finer", 2);
    const Variant v = parseVariant("sslpv:diffusion");
    const CaseRun out = evaluateCase(c, {v}, run);
    ASSERT_EQ(out.results.size(), 2u);
    const auto render = [&](int q) {
        methods::ParamSet params = v.variant.values;
        params.merge(v.settings[size_t(q)].values);
        methods::RenderOptions ro;
        ro.backend = v.variant.backend;
        return methods::renderImage(c.scene, v.method, params, ro).radiance;
    };
    const double expected =
        bench::compareImages(render(0), render(1), nullptr, nullptr, &out.reference.mask)
            .blocks[bench::ErrorReport::LUMINANCE]
            .relL1;
    EXPECT_GT(expected, 0.0);  // grid 16 and grid 32 differ
    EXPECT_NEAR(out.results[0].blockRelL1ToFiner, expected, 1e-12);
    EXPECT_LT(out.results[1].blockRelL1ToFiner, 0.0);  // nothing finer was rendered
}

TEST(EvaluationRun, CostUnitIsTimedBeforeAndAfterTheMethods) {
    // The Direct render is the unit of every cost ratio; timed only before the methods, one
    // burst of load at the start skewed a whole case's ratios. At least 3 runs before and 3
    // after, with a "direct" variant's own runs (here 1) among them.
    RunOptions run = quickRun("cost-unit", 1);
    std::vector<std::string> lines;
    run.progress = [&](const std::string& line) { lines.push_back(line); };
    const CaseRun out = evaluateCase(smokeCase(16), {parseVariant("direct")}, run);
    ASSERT_EQ(out.results.size(), 1u);
    EXPECT_GT(out.results[0].directCpuMs, 0.0);
    const auto unit = std::find_if(lines.begin(), lines.end(), [](const std::string& l) {
        return l.find("the unit of cost") != std::string::npos;
    });
    ASSERT_NE(unit, lines.end());
    EXPECT_NE(unit->find("median of 7"), std::string::npos) << *unit;
}

TEST(EvaluationReport, CsvHasTheColumnsThePlannerFitNeeds) {
    const std::string header = csvHeader();
    for (const char* column :
         {"case,", "method,", "setting,", "time_ms,", "direct_ms,", "cost_ratio,", "block_rel_l1,",
          "block_rel_rmse,", "mean_ratio,", "p95,", "noise_floor,", "block_rel_l1_to_finer,",
          "block_rel_l1_r,", "feature_optical_size,", "feature_back_lit_fraction,",
          "feature_lights"})
        EXPECT_NE(header.find(column), std::string::npos) << column;
    // Two results of one case: the CSV rows have the header's columns (a quoted setting with a
    // comma stays one field), the summary names the better one, the front holds both.
    const CachedReference ref = twoBlockReference(0.f);
    Result cheap, good;
    cheap.caseName = good.caseName = "two-blocks";
    cheap.variant = "direct";
    cheap.setting = "-";
    cheap.costRatio = cheap.cpuCostRatio = 1.0;
    good.variant = "dirpole";
    good.setting = "grid 16, 16 steps";
    good.costRatio = good.cpuCostRatio = 10.0;
    ImageRgb off = ref.mean;
    for (Rgb& p : off.pixels())
        p *= 1.3f;
    cheap.metrics = scoreImage(off, ref);
    good.metrics = scoreImage(ref.mean, ref);
    good.features = planner::SceneFeatures{};
    const std::string csv = toCsv({cheap, good});
    std::istringstream lines(csv);
    std::string line;
    const auto columns = [](const std::string& row) {
        size_t n = 1;
        bool quoted = false;
        for (char c : row) {
            quoted ^= c == '"';
            n += !quoted && c == ',';
        }
        return n;
    };
    std::getline(lines, line);
    const size_t n = columns(line);
    int rows = 0;
    while (std::getline(lines, line)) {
        EXPECT_EQ(columns(line), n) << line;
        ++rows;
    }
    EXPECT_EQ(rows, 2);
    const std::string summary = summaryMarkdown({cheap, good});
    EXPECT_NE(summary.find("| two-blocks | dirpole (grid 16, 16 steps) | 0.000 | 1.000"),
              std::string::npos)
        << summary;
    EXPECT_NE(summary.find("met"), std::string::npos);
    const std::string front = paretoMarkdown({cheap, good});
    EXPECT_NE(front.find("| direct |"), std::string::npos) << front;
    EXPECT_NE(front.find("dirpole"), std::string::npos) << front;
    RunInfo info;
    EXPECT_NE(gnuplotScript({cheap, good}, info).find("chart_two-blocks.dat"), std::string::npos);
}

TEST(EvaluationReport, ResultsReadBackAsWritten) {
    // What --report redraws from: the CSV and the run info round-trip through their parsers.
    const CachedReference ref = twoBlockReference(0.04f);
    Result r;
    r.caseName = "round-trip";
    r.group = "test";
    r.variant = "sslpv:paper";
    r.setting = "grid 16, 16 steps";  // quoted in the CSV
    r.quality = 2;
    r.backend = "gl";
    r.msMedian = 12.5;
    r.msMin = 11.0;
    r.runs = 3;
    r.directMs = 5.0;
    r.costRatio = 2.5;
    r.cpuMsMedian = 20.0;
    r.directCpuMs = 8.0;
    r.cpuCostRatio = 2.5;
    ImageRgb test = ref.mean;
    test.at(1, 1) = Rgb(2.f, 1.f, 0.5f);
    r.metrics = scoreImage(test, ref);
    r.noiseFloor = r.metrics.report.blocks[Metrics::LUM].relL1Floor;
    r.blockRelL1ToFiner = 0.0375;
    planner::SceneFeatures f;
    f.opticalSize = 123.5;
    f.insideVoxels = 4096;
    r.features = f;
    Result noFeatures = r;
    noFeatures.features.reset();
    noFeatures.blockRelL1ToFiner = -1.0;  // the finest setting: an empty cell
    const std::string csv = toCsv({r, noFeatures});
    const std::vector<Result> back = parseResultsCsv(csv, "results.csv");
    ASSERT_EQ(back.size(), 2u);
    EXPECT_EQ(toCsv(back), csv);
    ASSERT_TRUE(back[0].features);
    EXPECT_EQ(back[0].features->insideVoxels, 4096);
    EXPECT_DOUBLE_EQ(back[0].blockRelL1ToFiner, 0.0375);
    EXPECT_LT(back[1].blockRelL1ToFiner, 0.0);
    EXPECT_FALSE(back[1].features);
    EXPECT_THROW(parseResultsCsv(csvHeader() + "a,b\n", "bad.csv"), IoError);

    RunInfo info;
    info.suite = "default";
    info.command = "lucent-cli evaluate --suite default --out \"x\"";
    info.width = 64;
    info.height = 48;
    info.refSpp = 256;
    info.refSeed = 2;
    info.cases = {"a", "b"};
    info.noiseFloors = {0.01, 0.02};
    info.referenceSeconds = {3.0, 0.0};
    info.referenceSpp = {256, 2048};
    info.refFloor = 0.007;
    info.refMaxSpp = 8192;
    info.skipped = {"b: combined (8 spp): no GL"};
    const RunInfo again = parseRunInfoJson(toJson({}, info), "results.json");
    EXPECT_EQ(toJson({}, again), toJson({}, info));
    EXPECT_EQ(again.refSeed, 2);
    EXPECT_EQ(again.referenceSpp, (std::vector<int>{256, 2048}));
    EXPECT_DOUBLE_EQ(again.refFloor, 0.007);
    EXPECT_THROW(parseRunInfoJson("{", "bad.json"), IoError);
}

TEST(Evaluation, SteadyTimeLeavesOutRunsThatCompiledShaders) {
    // Where every run is within 1.5x of the fastest: the plain median (odd and even counts).
    EXPECT_DOUBLE_EQ(steadyMedian({35.0, 33.0, 34.0}), 34.0);
    EXPECT_DOUBLE_EQ(steadyMedian({30.0, 44.0, 31.0, 32.0}), 31.5);
    int dropped = -1;
    EXPECT_DOUBLE_EQ(steadyMedian({40.0}, &dropped), 40.0);
    EXPECT_EQ(dropped, 0);
    // Measured 2026-12-06 (lights-two's Direct brackets, one process): a run that compiled
    // shaders reads about 80 ms more; the median of 9 was one of them when five were.
    const std::vector<double> bracket = {29.9, 107.5, 30.1, 112.1, 30.3, 30.3, 30.6, 30.8, 30.9};
    EXPECT_DOUBLE_EQ(steadyMedian(bracket, &dropped), 30.3);
    EXPECT_EQ(dropped, 2);
    const std::vector<double> mostlySlow = {33.0, 110.0, 112.0, 108.0, 34.0, 115.0, 111.0};
    EXPECT_DOUBLE_EQ(steadyMedian(mostlySlow, &dropped), 33.5);
    EXPECT_EQ(dropped, 5);
    // The limit is inclusive: 1.5x the fastest is kept.
    EXPECT_DOUBLE_EQ(steadyMedian({20.0, 30.0, 30.5}, &dropped), 25.0);
    EXPECT_EQ(dropped, 1);
    EXPECT_THROW(steadyMedian({}), ValueError);
    EXPECT_THROW(steadyMedian({30.0, std::nan("")}), ValueError);
    EXPECT_THROW(steadyMedian({30.0, -1.0}), ValueError);
}

TEST(Evaluation, SppForANoiseFloorFallsAsOneOverTheRootOfTheSamples) {
    // Half the floor takes four times the samples; a third of it nine.
    EXPECT_EQ(sppForNoiseFloor(256, 0.02, 0.01, 8192), 1024);
    EXPECT_EQ(sppForNoiseFloor(256, 0.03, 0.01, 8192), 2304);
    // Rounded up to whole pilots: (0.02/0.015)² = 1.78 pilots -> 2.
    EXPECT_EQ(sppForNoiseFloor(256, 0.02, 0.015, 8192), 512);
    // Already there, or no room above the pilot: the pilot.
    EXPECT_EQ(sppForNoiseFloor(256, 0.005, 0.01, 8192), 256);
    EXPECT_EQ(sppForNoiseFloor(256, 0.0, 0.01, 8192), 256);
    EXPECT_EQ(sppForNoiseFloor(256, 0.05, 0.01, 128), 256);
    // Capped: 0.08 -> 0.005 would take 256 pilots.
    EXPECT_EQ(sppForNoiseFloor(256, 0.08, 0.005, 8192), 8192);
    EXPECT_THROW((void)sppForNoiseFloor(256, 0.02, 0.0, 8192), ValueError);
    EXPECT_THROW((void)sppForNoiseFloor(0, 0.02, 0.01, 8192), ValueError);
    EXPECT_THROW((void)sppForNoiseFloor(256, std::nan(""), 0.01, 8192), ValueError);
}

}  // namespace
}  // namespace lucent::evaluation
