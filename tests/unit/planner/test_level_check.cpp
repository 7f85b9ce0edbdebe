// SPDX-License-Identifier: MIT
/// @file
/// @brief Auto's level check (planner/LevelCheck.h): the rule steps down while the summed
/// differences between adjacent levels stay within the tolerance; the scene version measures
/// those differences as the block metric between the levels' renders of the scene's frame;
/// the front check replays it on an evaluation's measured differences.

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>
#include <lucent/planner/LevelCheck.h>
#include <lucent/scene/SceneFile.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

using namespace lucent;
using namespace lucent::planner;

namespace {

const std::vector<std::string> LEVELS = {"grid 16", "grid 32", "grid 64"};

/// Differences of levels 0→1 and 1→2.
std::function<double(size_t)> differences(double d01, double d12) {
    return [=](size_t i) { return i == 0 ? d01 : d12; };
}

}  // namespace

TEST(LevelCheck, RuleStepsDownWhileTheSummedDifferenceStaysWithinTheTolerance) {
    std::vector<LevelStep> steps;
    // 0.015 to go from 64 to 32, then 0.01 more to 16: 0.025 in all.
    EXPECT_EQ(coarsestEquivalentLevel(LEVELS, 2, differences(0.01, 0.015), 0.02, &steps), 1u);
    ASSERT_EQ(steps.size(), 2u);
    EXPECT_EQ(steps[0].coarser, "grid 32");
    EXPECT_EQ(steps[0].finer, "grid 64");
    EXPECT_DOUBLE_EQ(steps[0].difference, 0.015);
    EXPECT_TRUE(steps[0].taken);
    EXPECT_EQ(steps[1].coarser, "grid 16");
    EXPECT_FALSE(steps[1].taken);  // each step alone is within 0.02; their sum is not
    EXPECT_EQ(coarsestEquivalentLevel(LEVELS, 2, differences(0.01, 0.015), 0.025), 0u);
    // The first step too far: the choice stays.
    EXPECT_EQ(coarsestEquivalentLevel(LEVELS, 2, differences(0.0, 0.03), 0.02), 2u);
    // From the middle, only the levels below it.
    EXPECT_EQ(coarsestEquivalentLevel(LEVELS, 1, differences(0.01, 0.0), 0.02), 0u);
    // The cheapest level has nothing below it; a tolerance of 0 is no check.
    steps.clear();
    EXPECT_EQ(coarsestEquivalentLevel(LEVELS, 0, differences(0.0, 0.0), 0.02, &steps), 0u);
    EXPECT_TRUE(steps.empty());
    EXPECT_EQ(coarsestEquivalentLevel(LEVELS, 2, differences(0.0, 0.0), 0.0), 2u);
    // An unknown difference (not measured, NaN) ends the walk where it is.
    EXPECT_EQ(coarsestEquivalentLevel(LEVELS, 2, differences(0.0, -1.0), 0.02), 2u);
    EXPECT_EQ(coarsestEquivalentLevel(LEVELS, 2, differences(std::nan(""), 0.01), 0.02), 1u);
    EXPECT_THROW(coarsestEquivalentLevel(LEVELS, 3, differences(0, 0), 0.02), ValueError);
    EXPECT_THROW(coarsestEquivalentLevel(LEVELS, 2, differences(0, 0), -0.1), ValueError);
}

TEST(LevelCheck, ToleranceIsTheLargerOfTheAbsoluteAndTheRelativeToThePredictedError) {
    const LevelTolerance t{0.02, 1.0};
    EXPECT_DOUBLE_EQ(t.at(0.01), 0.02);
    EXPECT_DOUBLE_EQ(t.at(0.06), 0.06);
    EXPECT_DOUBLE_EQ((LevelTolerance{0.02, 0.5}.at(0.06)), 0.03);
    EXPECT_TRUE((LevelTolerance{0.0, 0.0}.off()));
    EXPECT_FALSE((LevelTolerance{0.0, 0.5}.off()));
}

TEST(LevelCheck, ModelLevelsFollowTheRegistrysQualityOrder) {
    Models models;
    for (const char* s : {"grid 64", "grid 16", "grid 32"}) {
        CandidateModel m;
        m.method = "sslpv:diffusion";
        m.setting = s;
        models.candidates.push_back(m);
    }
    EXPECT_EQ(modelLevels(models, "sslpv:diffusion"), LEVELS);
    EXPECT_TRUE(modelLevels(models, "sslpv:paper").empty());  // no such candidates
    EXPECT_TRUE(modelLevels(models, "no-such-method").empty());
}

TEST(LevelCheck, FrontCheckReplaysTheCheckOnTheMeasuredDifferences) {
    // Grid 64 predicted best; measured, grid 32 reads nearly the same for a third of the time.
    Models models;
    const double costs[] = {1.0, 3.0, 9.0};
    const double errors[] = {0.2, 0.06, 0.05};
    for (size_t i = 0; i < LEVELS.size(); ++i) {
        CandidateModel m;
        m.method = "sslpv:diffusion";
        m.setting = LEVELS[i];
        m.cost = {std::log(costs[i]), 0, 0};
        m.error.assign(errorTermNames().size(), 0.0);
        m.error[0] = std::log(errors[i]);
        models.candidates.push_back(m);
    }
    std::vector<MeasuredRow> rows;
    const double toFiner[] = {0.15, 0.03, -1.0};
    for (size_t i = 0; i < LEVELS.size(); ++i) {
        MeasuredRow r;
        r.caseName = "case";
        r.method = "sslpv:diffusion";
        r.setting = LEVELS[i];
        r.costRatio = costs[i];
        r.blockRelL1 = errors[i];
        r.noiseFloor = 0.015;
        r.blockRelL1ToFiner = toFiner[i];
        r.features.opticalSize = 50;
        r.features.albedo = 0.9;
        r.features.eta = 1.3;
        rows.push_back(r);
    }
    // Off: the models' pick, 3× the cheapest point at its error.
    const FrontCheck off = checkAgainstFront(rows, models, 20.0, 0.1, {0.0, 0.0})[0];
    EXPECT_EQ(off.chosen, "sslpv:diffusion grid 64");
    EXPECT_TRUE(off.planned.empty());
    EXPECT_DOUBLE_EQ(off.timeRatio, 3.0);
    // On (0.03 ≤ max(0.02, 1 × the predicted 0.05)): grid 32; grid 16 (0.15 more) is not.
    const FrontCheck on = checkAgainstFront(rows, models, 20.0, 0.1, LevelTolerance{})[0];
    EXPECT_EQ(on.chosen, "sslpv:diffusion grid 32");
    EXPECT_EQ(on.planned, "sslpv:diffusion grid 64");
    EXPECT_DOUBLE_EQ(on.timeRatio, 1.0);
    EXPECT_TRUE(on.choseBest);  // 0.06 is within the floor of grid 64's 0.05
    // A tolerance below the measured difference keeps the pick.
    EXPECT_EQ(checkAgainstFront(rows, models, 20.0, 0.1, {0.02, 0.5})[0].chosen,
              "sslpv:diffusion grid 64");
    // Rows without the column (older files) keep the pick.
    for (MeasuredRow& r : rows)
        r.blockRelL1ToFiner = -1.0;
    EXPECT_EQ(checkAgainstFront(rows, models, 20.0, 0.1, LevelTolerance{})[0].chosen,
              "sslpv:diffusion grid 64");
    EXPECT_THROW(checkAgainstFront(rows, models, 20.0, 0.1, {-0.1, 1.0}), ValueError);
}

TEST(LevelCheck, SceneCheckComparesTheLevelsRendersOfTheScenesFrame) {
    Scene scene = loadScene(std::string(LUCENT_SCENES_DIR) + "/minimal.json");
    scene.camera.width = 96;
    scene.camera.height = 64;
    AutoChoice choice;
    choice.method = "sslpv";
    choice.variant = "diffusion";
    choice.setting = "grid 32";
    choice.params = resolveCandidate("sslpv:diffusion", "grid 32").params;
    choice.plan.chosen.error = 0.05;
    const Models& models = defaultModels();
    ASSERT_EQ(modelLevels(models, "sslpv:diffusion"), LEVELS);

    // The difference is the block metric of grid 16's render against grid 32's, on the
    // camera's view narrowed to 48 pixels (the aspect kept).
    LevelCheckOptions options;
    options.width = 48;
    options.tolerance = {1.0, 0.0};
    const LevelCheck wide = checkLevels(scene, models, choice, options);
    ASSERT_EQ(wide.steps.size(), 1u);
    EXPECT_TRUE(wide.steps[0].taken);
    EXPECT_EQ(wide.setting, "grid 16");
    Scene small = scene;
    small.camera.width = 48;
    small.camera.height = 32;
    const auto render = [&](const std::string& level) {
        return renderCandidate(small, "sslpv:diffusion", level).radiance;
    };
    const ImageRgb coarse = render("grid 16"), fine = render("grid 32");
    ASSERT_EQ(coarse.width(), 48);
    ASSERT_EQ(coarse.height(), 32);
    const std::vector<uint8_t> mask = bench::maskOfNonBlack(coarse, fine);
    const double expected =
        bench::compareImages(coarse, fine, nullptr, nullptr, &mask).blocks[3].relL1;
    EXPECT_GT(expected, 0.0);  // the grids differ
    EXPECT_NEAR(wide.steps[0].difference, expected, 1e-9);
    EXPECT_NE(wide.note.find("grid 16: grid 32 changes the image by"), std::string::npos)
        << wide.note;

    // Applied: the params and the plan's candidate are grid 16's, the reason says why.
    AutoChoice applied = choice;
    applyLevelCheck(applied, models, wide);
    EXPECT_EQ(applied.setting, "grid 16");
    EXPECT_EQ(applied.params.toString(),
              resolveCandidate("sslpv:diffusion", "grid 16").params.toString());
    EXPECT_EQ(models.candidates[applied.plan.choice].setting, "grid 16");
    // The reason leads with what runs, then why, then the models' reason for their pick.
    EXPECT_EQ(applied.plan.reason.rfind("sslpv:diffusion grid 16 by the level check: grid 32 "
                                        "changes the image by ",
                                        0),
              0u)
        << applied.plan.reason;
    EXPECT_NE(applied.plan.reason.find("; the models' pick: "), std::string::npos);

    // A tolerance below the difference keeps the choice and says by how much it differs.
    options.tolerance = {expected / 2, 0.0};
    const LevelCheck tight = checkLevels(scene, models, choice, options);
    EXPECT_EQ(tight.setting, "grid 32");
    ASSERT_EQ(tight.steps.size(), 1u);
    EXPECT_FALSE(tight.steps[0].taken);
    EXPECT_NE(tight.note.find("grid 32 kept: grid 16 differs by"), std::string::npos) << tight.note;
    AutoChoice kept = choice;
    applyLevelCheck(kept, models, tight);
    EXPECT_EQ(kept.setting, "grid 32");
    EXPECT_EQ(kept.params.toString(), choice.params.toString());

    // Off, or nothing cheaper: no render at all.
    options.tolerance = {0.0, 0.0};
    EXPECT_TRUE(checkLevels(scene, models, choice, options).steps.empty());
    AutoChoice cheapest = choice;
    cheapest.setting = "grid 16";
    options.tolerance = {1.0, 0.0};
    EXPECT_TRUE(checkLevels(scene, models, cheapest, options).steps.empty());
    options.width = 4;
    EXPECT_THROW(checkLevels(scene, models, choice, options), ValueError);
}

TEST(LevelCheck, AFailedRenderKeepsTheModelsLevelAndSaysWhy) {
    // The check only saves time: `render --method auto` must not fail because of it.
    Scene empty = loadScene(std::string(LUCENT_SCENES_DIR) + "/minimal.json");
    empty.objects.clear();  // nothing to render: every method throws
    AutoChoice choice;
    choice.method = "sslpv";
    choice.variant = "diffusion";
    choice.setting = "grid 32";
    choice.params = resolveCandidate("sslpv:diffusion", "grid 32").params;
    choice.plan.reason = "planned";
    std::string said;
    LevelCheckOptions options;
    options.render.log = [&](const std::string& m) { said += m; };
    runLevelCheck(empty, defaultModels(), choice, options);
    EXPECT_EQ(choice.setting, "grid 32");
    EXPECT_EQ(choice.plan.reason, "planned");
    EXPECT_NE(said.find("level check skipped ("), std::string::npos) << said;
    // The caller's own mistakes still throw.
    options.width = 4;
    EXPECT_THROW(runLevelCheck(empty, defaultModels(), choice, options), ValueError);
}
