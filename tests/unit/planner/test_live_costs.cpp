// SPDX-License-Identifier: MIT
/// @file
/// @brief The live preview's costs (planner/LiveCosts.h): the file format refuses what it cannot
/// use with a message, the live models carry the offline error models and a constant measured
/// cost, the shipped table names only candidates the shipped models and the registry know, and
/// Auto with a required GL backend plans with them.

#include <lucent/core/Error.h>
#include <lucent/methods/Registry.h>
#include <lucent/planner/AutoMethod.h>
#include <lucent/planner/LiveCosts.h>
#include <lucent/scene/SceneFile.h>

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

using namespace lucent;
using namespace lucent::planner;

namespace {

std::string table(const std::string& entries) {
    return R"({"format": "lucent-planner-live-costs", "version": 1, "source": "test",
              "entries": [)" +
           entries + "]}";
}

void expectRefused(const std::string& json, const std::string& said) {
    try {
        parseLiveCosts(json, "costs.json");
        FAIL() << "accepted: " << json;
    } catch (const ValueError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("costs.json"), std::string::npos) << what;
        EXPECT_NE(what.find(said), std::string::npos) << what;
    }
}

}  // namespace

TEST(LiveCosts, FormatRoundTripsAndRefusesWhatItCannotUse) {
    const LiveCosts c = parseLiveCosts(
        table(R"({"method": "dirpole", "setting": "128 spp", "stroke_ratio": 4.5})"), "t");
    ASSERT_EQ(c.entries.size(), 1u);
    EXPECT_EQ(c.entries[0].method, "dirpole");
    EXPECT_EQ(c.entries[0].setting, "128 spp");
    EXPECT_DOUBLE_EQ(c.entries[0].strokeRatio, 4.5);
    const LiveCosts again = parseLiveCosts(formatLiveCosts(c), "t");
    ASSERT_EQ(again.entries.size(), 1u);
    EXPECT_DOUBLE_EQ(again.entries[0].strokeRatio, 4.5);
    EXPECT_EQ(again.source, "test");
    // Whether the app's host share is in the ratios: absent means not (a headless calibration
    // of an older build); it round-trips; anything but a boolean is refused.
    EXPECT_FALSE(c.hostIncluded);
    LiveCosts withHost = c;
    withHost.hostIncluded = true;
    EXPECT_TRUE(parseLiveCosts(formatLiveCosts(withHost), "t").hostIncluded);
    EXPECT_FALSE(again.hostIncluded);
    {
        std::string json = table(R"({"method": "dirpole", "setting": "8 spp", "stroke_ratio": 2})");
        json.insert(1, R"("host_included": "yes", )");
        expectRefused(json, "host_included");
    }

    expectRefused("{", "not valid JSON");
    expectRefused(R"({"format": "lucent-planner-models"})", "not a live costs file");
    expectRefused(R"({"format": "lucent-planner-live-costs", "version": 9, "entries": []})",
                  "version 9");
    expectRefused(table(""), "non-empty");
    expectRefused(table(R"({"method": "dirpole", "stroke_ratio": 2})"), "without");
    expectRefused(table(R"({"method": "dirpole", "setting": "8 spp"})"), "stroke_ratio");
    expectRefused(table(R"({"method": "dirpole", "setting": "8 spp", "stroke_ratio": 0})"), "> 0");
    expectRefused(table(R"({"method": "dirpole", "setting": "8 spp", "stroke_ratio": -1e400})"),
                  "");
}

TEST(LiveCosts, LiveModelsKeepTheErrorModelAndPredictTheMeasuredCost) {
    const Models& offline = defaultModels();
    ASSERT_FALSE(offline.candidates.empty());
    const CandidateModel& m = offline.candidates.back();
    LiveCosts live;
    live.entries = {{m.method, m.setting, 3.25}, {"photon-beams", "8 spp", 2.0}};
    std::vector<std::string> missing;
    const Models lm = liveModels(offline, live, &missing);
    ASSERT_EQ(lm.candidates.size(), 1u);
    ASSERT_EQ(missing, std::vector<std::string>{"photon-beams 8 spp"});
    SceneFeatures a, b;
    a.opticalSize = 10;
    a.pixelsCovered = 100;
    a.imagePixels = 10000;
    a.lights = 1;
    b.opticalSize = 500;
    b.pixelsCovered = 9000;
    b.imagePixels = 10000;
    b.lights = 3;
    b.backLitFraction = 0.8;
    for (const SceneFeatures& f : {a, b}) {
        EXPECT_NEAR(predictCost(lm.candidates[0], f), 3.25, 1e-12);
        EXPECT_DOUBLE_EQ(predictError(lm.candidates[0], f), predictError(m, f));
    }
}

// The shipped table: every entry has a shipped error model (else Auto silently loses it), and
// resolves to a registry method with a GL pass (the preview runs only those).
TEST(LiveCosts, ShippedTableMatchesTheModelsAndTheRegistry) {
    const LiveCosts& live = defaultLiveCosts();
    ASSERT_FALSE(live.entries.empty());
    EXPECT_TRUE(live.hostIncluded) << "the shipped table is the app's harness: Qt's share is in it";
    std::vector<std::string> missing;
    const Models lm = liveModels(defaultModels(), live, &missing);
    EXPECT_TRUE(missing.empty()) << missing.front();
    EXPECT_EQ(lm.candidates.size(), live.entries.size());
    for (const LiveCost& c : live.entries) {
        const CandidateRun run = resolveCandidate(c.method, c.setting);
        EXPECT_TRUE(methods::find(run.method).caps.gl) << c.method;
        EXPECT_NE(run.backend, methods::Backend::Cpu) << c.method << " runs on the CPU only";
    }
    EXPECT_THROW(resolveCandidate("dirpole", "3 spp"), ValueError);
    EXPECT_THROW(resolveCandidate("sslpv:nonsense", "grid 32"), ValueError);
}

// Auto's live preview runs each candidate with the live defaults of what the candidate leaves
// open; its error model is the offline render's. So every parameter that shapes the converged
// picture must be the same live and offline. The exceptions, each how far the live preview
// goes rather than what it converges to, or measured not to move the default scene:
// SSLPV's steps, stop, brick-stop and refine-steps (the live propagation's length: 32 steps per
// frame, carried on over idle frames until the per-brick stop ends it, docs/planner.md), the
// image-space dipoles' layered-depth (8 voxels live, 16 offline: 0 difference there) and
// combined's auto-skip (off live: 0 difference there).
TEST(LiveCosts, EveryCandidateRunsLiveWhatItWasEvaluatedAs) {
    const std::set<std::string> progress = {"steps",        "stop",          "brick-stop",
                                            "refine-steps", "layered-depth", "auto-skip"};
    for (const LiveCost& c : defaultLiveCosts().entries) {
        SCOPED_TRACE(c.method + " " + c.setting);
        const CandidateRun run = resolveCandidate(c.method, c.setting);
        const auto live = methods::create(run.method, run.params, {methods::Backend::Gl, true, {}});
        const auto offline =
            methods::create(run.method, run.params, {methods::Backend::Gl, false, {}});
        for (const methods::ParamDescriptor& d : methods::find(run.method).params) {
            if (progress.count(d.name))
                continue;
            if (d.name == "attenuation" &&
                run.params.toString().find("mode=paper") == std::string::npos)
                continue;  // SSLPV's paper mode only (the others ignore it)
            EXPECT_EQ(live->params().text(d.name), offline->params().text(d.name)) << d.name;
        }
    }
}

// Auto in the preview: the GL backend is required, the live costs decide what fits the frame.
TEST(LiveCosts, AutoWithTheLiveModelsFitsTheBudgetOrTakesTheCheapest) {
    Scene scene = loadScene(std::string(LUCENT_SCENES_DIR) + "/minimal.json");
    const Models lm = liveModels(defaultModels(), defaultLiveCosts());
    double cheapest = INFINITY, second = INFINITY;
    for (const LiveCost& c : defaultLiveCosts().entries) {
        second = std::min(second, std::max(cheapest, c.strokeRatio));
        cheapest = std::min(cheapest, c.strokeRatio);
    }
    ASSERT_LT(cheapest, second) << "two candidates cost the same";
    Budget budget;
    budget.directMs = 10.0;
    // Only the cheapest fits: a budget between it and the next (the table's ratios can be
    // within 1 % of each other: 6.74 and 6.76 in the run of 2026-12-07).
    budget.frameMs = 0.5 * (cheapest + second) * budget.directMs;
    budget.overrunTolerance = 0.0;
    AutoChoice c = chooseMethod(scene, lm, budget, true, nullptr, methods::Backend::Gl);
    EXPECT_EQ(c.backend, methods::Backend::Gl);
    EXPECT_TRUE(c.plan.chosen.fits) << c.plan.reason;
    EXPECT_NEAR(c.plan.chosen.ms, cheapest * budget.directMs, 1e-9);
    // A budget nothing fits, no overrun allowed: the cheapest, said to be over budget.
    budget.frameMs = cheapest * budget.directMs * 0.5;
    c = chooseMethod(scene, lm, budget, true, nullptr, methods::Backend::Gl);
    EXPECT_FALSE(c.plan.chosen.fits);
    EXPECT_NEAR(c.plan.chosen.ms, cheapest * budget.directMs, 1e-9);
    EXPECT_NE(c.plan.reason.find("over budget"), std::string::npos) << c.plan.reason;
    // No budget: the least predicted error among them.
    budget.frameMs = INFINITY;
    c = chooseMethod(scene, lm, budget, true, nullptr, methods::Backend::Gl);
    const SceneFeatures f = c.features;
    for (const CandidateModel& m : lm.candidates)
        EXPECT_GE(predictError(m, f) * (1.0 + budget.errorTolerance), c.plan.chosen.error)
            << m.method << " " << m.setting;
}
