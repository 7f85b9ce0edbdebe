// SPDX-License-Identifier: MIT
/// @file
/// @brief Candidates measured on one scene (planner/MeasureScene.h): the cost is the render's
/// time over the Direct render's, the error is the Reference dock's block relative L1 against
/// the given reference, the measured models predict exactly what was measured, and a cancel
/// stops before the next render.

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>
#include <lucent/planner/LiveCosts.h>
#include <lucent/planner/MeasureScene.h>
#include <lucent/reference/PathTracer.h>
#include <lucent/scene/SceneFile.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>

using namespace lucent;
using namespace lucent::planner;

namespace {

/// The minimal scene at a small size: a measurement renders every candidate once.
Scene smallScene() {
    Scene scene = loadScene(std::string(LUCENT_SCENES_DIR) + "/minimal.json");
    scene.camera.width = 48;
    scene.camera.height = 32;
    return scene;
}

/// The live preview's cheapest candidate: what the app's measure button renders too.
size_t cheapestLive(const Models& live) {
    size_t best = 0;
    const SceneFeatures f;
    for (size_t i = 1; i < live.candidates.size(); ++i)
        if (predictCost(live.candidates[i], f) < predictCost(live.candidates[best], f))
            best = i;
    return best;
}

}  // namespace

TEST(MeasureScene, CostIsTheRatioToDirectAndErrorIsTheBlockMetric) {
    const Scene scene = smallScene();
    const Models live = liveModels(defaultModels(), defaultLiveCosts());
    ASSERT_FALSE(live.candidates.empty());
    MeasureOptions opt;
    opt.which = {cheapestLive(live)};
    opt.render.backend = methods::Backend::Gl;  // as the preview runs them
    size_t calls = 0;
    opt.progress = [&](size_t done, size_t total, const CandidateMeasurement* last) {
        EXPECT_EQ(total, 1u);
        EXPECT_EQ(done, calls);
        EXPECT_EQ(last != nullptr, done > 0);
        ++calls;
    };
    const SceneMeasurement first = measureCandidates(scene, live, opt);
    EXPECT_EQ(calls, 2u);  // after Direct, after the candidate
    EXPECT_FALSE(first.cancelled);
    EXPECT_GT(first.directMs, 0.0);
    ASSERT_EQ(first.candidates.size(), 1u);
    const CandidateMeasurement& a = first.candidates[0];
    ASSERT_TRUE(a.ok()) << a.failed;
    EXPECT_EQ(a.method, live.candidates[opt.which[0]].method);
    EXPECT_EQ(a.setting, live.candidates[opt.which[0]].setting);
    EXPECT_GT(a.ms, 0.0);
    EXPECT_DOUBLE_EQ(a.costRatio, a.ms / first.directMs);
    EXPECT_LT(a.blockRelL1, 0.0);  // no reference, no error
    ASSERT_EQ(a.radiance.width(), 48);
    ASSERT_EQ(a.radiance.height(), 32);

    // A "reference" twice as bright as the first render: the error is the dock's metric of
    // the second render against it (compareImages, luminance blocks, over the mask).
    ImageRgb ref = a.radiance;
    for (Rgb& p : ref.pixels())
        p = p * 2.f;
    const std::vector<uint8_t> mask = bench::maskFromImage(ref);
    opt.reference = &ref;
    opt.mask = &mask;
    opt.progress = nullptr;
    const SceneMeasurement second = measureCandidates(scene, live, opt);
    ASSERT_EQ(second.candidates.size(), 1u);
    const CandidateMeasurement& b = second.candidates[0];
    ASSERT_TRUE(b.ok()) << b.failed;
    const double expected = bench::compareImages(b.radiance, ref, nullptr, nullptr, &mask)
                                .blocks[bench::ErrorReport::LUMINANCE]
                                .relL1;
    EXPECT_DOUBLE_EQ(b.blockRelL1, expected);
    // Were the two renders equal, |x − 2x| / 2x = 1/2 in every block; the preview methods'
    // frames are deterministic, so they are within float rounding of it.
    if (b.radiance.pixels() == a.radiance.pixels()) {
        EXPECT_NEAR(b.blockRelL1, 0.5, 1e-5);
    }

    // The measured models predict the measurement on any features; the others are unchanged.
    const Models measured = measuredModels(live, second);
    ASSERT_EQ(measured.candidates.size(), live.candidates.size());
    SceneFeatures f1, f2;
    f2.pixelsCovered = 500.0;
    f2.imagePixels = 1000.0;
    f2.opticalSize = 30.0;
    f2.backLitFraction = 0.8;
    for (size_t i = 0; i < live.candidates.size(); ++i)
        for (const SceneFeatures& f : {f1, f2}) {
            if (i == opt.which[0]) {
                EXPECT_NEAR(predictCost(measured.candidates[i], f), b.costRatio,
                            1e-12 * b.costRatio);
                EXPECT_NEAR(predictError(measured.candidates[i], f), b.blockRelL1,
                            1e-12 * b.blockRelL1);
            } else {
                EXPECT_DOUBLE_EQ(predictCost(measured.candidates[i], f),
                                 predictCost(live.candidates[i], f));
                EXPECT_DOUBLE_EQ(predictError(measured.candidates[i], f),
                                 predictError(live.candidates[i], f));
            }
        }
    // Errors only (the live preview's use): the cost models stay the live ones.
    const Models errorsOnly = measuredModels(live, second, MeasuredParts::ErrorsOnly);
    for (const SceneFeatures& f : {f1, f2}) {
        const size_t i = opt.which[0];
        EXPECT_DOUBLE_EQ(predictCost(errorsOnly.candidates[i], f),
                         predictCost(live.candidates[i], f));
        EXPECT_NEAR(predictError(errorsOnly.candidates[i], f), b.blockRelL1, 1e-12 * b.blockRelL1);
    }
}

TEST(MeasureScene, CancelStopsBeforeTheNextRenderAndWrongSizesAreRefused) {
    const Scene scene = smallScene();
    const Models live = liveModels(defaultModels(), defaultLiveCosts());
    std::atomic<bool> cancel{true};
    MeasureOptions opt;
    opt.cancel = &cancel;
    opt.render.backend = methods::Backend::Gl;
    const SceneMeasurement m = measureCandidates(scene, live, opt);
    EXPECT_TRUE(m.cancelled);
    EXPECT_TRUE(m.candidates.empty());
    // Nothing measured: the models stay as they were.
    const Models same = measuredModels(live, m);
    EXPECT_EQ(same.candidates[0].cost, live.candidates[0].cost);

    const ImageRgb wrong(47, 32);
    MeasureOptions sized;
    sized.reference = &wrong;
    EXPECT_THROW(measureCandidates(scene, live, sized), ValueError);
    MeasureOptions outOfRange;
    outOfRange.which = {live.candidates.size()};
    EXPECT_THROW(measureCandidates(scene, live, outOfRange), ValueError);
}

// Auto measuring on its own: the exact reference of the frame at the asked width (the camera's
// aspect kept), then each candidate against it, net of the reference's noise (the
// evaluation's number). Deterministic: the same reference rendered apart gives the same errors.
TEST(MeasureScene, OwnReferenceIsTheExactImageOfTheFrameAtTheAskedWidth) {
    const Scene scene = smallScene();  // 48 × 32
    const Models live = liveModels(defaultModels(), defaultLiveCosts());
    OwnReferenceOptions opt;
    opt.width = 24;
    opt.referenceSpp = 16;
    opt.which = {cheapestLive(live)};
    opt.render.backend = methods::Backend::Gl;
    const OwnReferenceMeasurement m = measureWithOwnReference(scene, live, opt);
    EXPECT_EQ(m.width, 24);
    EXPECT_EQ(m.height, 16);
    EXPECT_EQ(m.referenceSpp, 16);
    EXPECT_GT(m.referenceNoise, 0.0);
    ASSERT_EQ(m.measurement.candidates.size(), 1u);
    const CandidateMeasurement& c = m.measurement.candidates[0];
    ASSERT_TRUE(c.ok()) << c.failed;
    ASSERT_EQ(c.radiance.width(), 24);

    Scene small = scene;
    small.camera.width = 24;
    small.camera.height = 16;
    reference::ReferenceOptions ro;
    ro.spp = 16;
    const reference::ReferenceImage ref = reference::renderReference(small, ro);
    const std::vector<uint8_t> mask = bench::maskFromImage(ref.coverage);
    const bench::ErrorReport e =
        bench::compareImages(c.radiance, ref.mean, &ref.variance, nullptr, &mask);
    EXPECT_DOUBLE_EQ(c.blockRelL1, e.blocks[bench::ErrorReport::LUMINANCE].relL1Net);
    EXPECT_DOUBLE_EQ(m.referenceNoise, e.blocks[bench::ErrorReport::LUMINANCE].relL1Floor);

    opt.width = 4;
    EXPECT_THROW(measureWithOwnReference(scene, live, opt), ValueError);
    opt.width = 24;
    opt.referenceSpp = 2;
    EXPECT_THROW(measureWithOwnReference(scene, live, opt), ValueError);
}

// chooseByMeasuring: the candidates within the budget measured, then the plan made with their
// measured errors: the least measured error wins unless a cheaper one is within 10 % plus the
// reference's noise of it. A cancelled measurement keeps the models' plan.
TEST(MeasureScene, ChoosingByMeasuringTakesTheLeastMeasuredErrorWithinTheNoise) {
    const Scene scene = smallScene();
    Models three = liveModels(defaultModels(), defaultLiveCosts());
    std::erase_if(three.candidates, [](const CandidateModel& c) {
        return c.setting != "grid 16" || c.method == "sslpv:calibrated";
    });
    ASSERT_EQ(three.candidates.size(), 2u);  // paper and diffusion at grid 16
    Budget budget;
    budget.frameMs = std::numeric_limits<double>::infinity();
    budget.directMs = 10.0;
    const AutoChoice planned =
        chooseMethod(scene, three, budget, true, nullptr, methods::Backend::Gl);
    OwnReferenceOptions opt;
    opt.width = 24;
    opt.referenceSpp = 16;
    opt.render.backend = methods::Backend::Gl;
    const MeasuredChoice m = chooseByMeasuring(scene, three, planned, budget, true, opt, {});
    ASSERT_EQ(m.measurement.measurement.candidates.size(), 2u);
    double least = INFINITY;
    for (const CandidateMeasurement& c : m.measurement.measurement.candidates) {
        ASSERT_TRUE(c.ok()) << c.failed;
        least = std::min(least, c.blockRelL1);
    }
    const CandidateModel& chosen = three.candidates[m.choice.plan.choice];
    const auto it = std::find_if(
        m.measurement.measurement.candidates.begin(), m.measurement.measurement.candidates.end(),
        [&](const CandidateMeasurement& c) {
            return c.method == chosen.method && c.setting == chosen.setting;
        });
    ASSERT_NE(it, m.measurement.measurement.candidates.end());
    EXPECT_LE(it->blockRelL1, least * 1.1 + m.measurement.referenceNoise);
    EXPECT_NEAR(m.choice.plan.chosen.error, std::max(it->blockRelL1, 1e-6), 1e-9);
    EXPECT_EQ(m.choice.plan.reason.rfind("errors measured on this scene: ", 0), 0u)
        << m.choice.plan.reason;

    std::atomic<bool> cancel{true};
    opt.cancel = &cancel;
    const MeasuredChoice kept = chooseByMeasuring(scene, three, planned, budget, true, opt, {});
    EXPECT_TRUE(kept.measurement.measurement.cancelled);
    EXPECT_EQ(kept.choice.plan.choice, planned.plan.choice);
    EXPECT_EQ(kept.choice.plan.reason, planned.plan.reason);
}
