// SPDX-License-Identifier: MIT
/// @file
/// @brief The planner's cost and error models: the fit recovers known log-linear models, its
/// leave-one-out error is honest, the evaluation CSV reader and the models file reject what
/// they cannot use with a message, the shipped models match the method registry, and Auto
/// resolves a choice to parameters the registry renders (and leaves out what cannot render).

#include <lucent/core/Error.h>
#include <lucent/methods/Registry.h>
#include <lucent/planner/AutoMethod.h>
#include <lucent/planner/Models.h>
#include <lucent/scene/SceneFile.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

using namespace lucent;
using namespace lucent::planner;

namespace {

/// Features spread over the ranges the terms are scaled for.
SceneFeatures randomFeatures(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    SceneFeatures f;
    f.opticalSize = std::pow(10.0, 3.0 * u(rng));
    f.albedo = 0.5 + 0.5 * u(rng);
    f.sigmaTVariation = u(rng);
    f.albedoVariation = 0.3 * u(rng);
    f.meanAbsG = 0.9 * u(rng);
    f.eta = 1.0 + u(rng);
    f.backLitFraction = u(rng);
    f.curvature = 1.5 * u(rng);
    f.thinFraction = u(rng);
    f.imagePixels = 10000;
    f.pixelsCovered = 10000 * u(rng);
    f.lights = 1 + int(3 * u(rng));
    return f;
}

/// Rows of one candidate from exact log-linear models.
std::vector<MeasuredRow> exactRows(const std::vector<double>& cost,
                                   const std::vector<double>& error, int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::vector<MeasuredRow> rows;
    for (int i = 0; i < n; ++i) {
        MeasuredRow r;
        r.caseName = "case" + std::to_string(i);
        r.method = "dipole";
        r.setting = "8 spp";
        r.features = randomFeatures(rng);
        double lc = 0, le = 0;
        const std::vector<double> tc = costTerms(r.features), te = errorTerms(r.features);
        for (size_t k = 0; k < tc.size(); ++k)
            lc += cost[k] * tc[k];
        for (size_t k = 0; k < te.size(); ++k)
            le += error[k] * te[k];
        r.costRatio = std::exp(lc);
        r.blockRelL1 = std::exp(le);
        rows.push_back(r);
    }
    return rows;
}

const std::vector<double> COST = {1.5, 0.8, 0.3};
const std::vector<double> ERROR = {-2.0, 0.5, 1.0, 0.7, -0.4, 0.6, 0.9, 1.2, -0.3, 0.2};

std::string writeTemp(const std::string& name, const std::string& text) {
    const std::string path = (std::filesystem::temp_directory_path() / name).string();
    std::ofstream(path) << text;
    return path;
}

/// A measured row of candidate `method` at setting "s" for the front checks.
MeasuredRow frontRow(const std::string& caseName, const std::string& method, double cost,
                     double error, double opticalSize, double meanAbsG = 0.0) {
    MeasuredRow r;
    r.caseName = caseName;
    r.method = method;
    r.setting = "s";
    r.costRatio = cost;
    r.blockRelL1 = error;
    r.features.opticalSize = opticalSize;
    r.features.albedo = 0.9;
    r.features.eta = 1.3;
    r.features.meanAbsG = meanAbsG;
    return r;
}

/// Two scene-independent candidates: "fast s" at 1× Direct and "slow s" at 10×, predicting
/// the given errors.
Models fastAndSlow(double fastError, double slowError) {
    Models models;
    CandidateModel fast, slow;
    fast.method = "fast";
    slow.method = "slow";
    fast.setting = slow.setting = "s";
    fast.cost = {std::log(1.0), 0, 0};
    slow.cost = {std::log(10.0), 0, 0};
    fast.error.assign(errorTermNames().size(), 0.0);
    slow.error = fast.error;
    fast.error[0] = std::log(fastError);
    slow.error[0] = std::log(slowError);
    models.candidates = {fast, slow};
    return models;
}

}  // namespace

TEST(PlannerModels, TermsMatchTheirNames) {
    SceneFeatures f;
    EXPECT_EQ(costTerms(f).size(), costTermNames().size());
    EXPECT_EQ(errorTerms(f).size(), errorTermNames().size());
    ASSERT_EQ(COST.size(), costTermNames().size());
    ASSERT_EQ(ERROR.size(), errorTermNames().size());
}

TEST(PlannerModels, FitRecoversAnExactLogLinearModel) {
    // 40 cases, 10 error terms, no noise, no ridge: least squares is exact (to rounding).
    const Models m = fitModels(exactRows(COST, ERROR, 40, 1), 0.0);
    ASSERT_EQ(m.candidates.size(), 1u);
    const CandidateModel& c = m.candidates[0];
    EXPECT_EQ(c.cases, 40);
    for (size_t k = 0; k < COST.size(); ++k)
        EXPECT_NEAR(c.cost[k], COST[k], 1e-8) << costTermNames()[k];
    for (size_t k = 0; k < ERROR.size(); ++k)
        EXPECT_NEAR(c.error[k], ERROR[k], 1e-7) << errorTermNames()[k];
    EXPECT_LT(c.costLogRms, 1e-8);
    EXPECT_LT(c.errorLogRms, 1e-7);
    // Predictions on a scene it has not seen.
    std::mt19937 rng(99);
    const SceneFeatures f = randomFeatures(rng);
    double le = 0;
    for (size_t k = 0; k < ERROR.size(); ++k)
        le += ERROR[k] * errorTerms(f)[k];
    EXPECT_NEAR(predictError(c, f), std::exp(le), 1e-6 * std::exp(le));
}

TEST(PlannerModels, RidgeShrinksTowardTheMeanAndLeaveOneOutSeesNoise) {
    // With 4 cases and 10 terms, an unregularised fit would interpolate noise; the ridge keeps
    // the slope small and the leave-one-out RMS reports the noise instead of hiding it.
    std::vector<MeasuredRow> rows = exactRows(COST, ERROR, 4, 2);
    std::mt19937 rng(3);
    std::normal_distribution<double> noise(0.0, 0.3);
    for (MeasuredRow& r : rows)
        r.blockRelL1 *= std::exp(noise(rng));
    const Models strong = fitModels(rows, 10.0);
    double slope = 0;
    for (size_t k = 1; k < ERROR.size(); ++k)
        slope += std::abs(strong.candidates[0].error[k]);
    EXPECT_LT(slope, 0.1);  // λ = 10 against terms of order one: slopes ≈ 1/λ of the data's
    EXPECT_GT(strong.candidates[0].errorLogRms, 0.05);  // the 0.3 noise (plus the model) shows
}

TEST(PlannerModels, CandidatesNeedTwoCasesAndUsableRows) {
    std::vector<MeasuredRow> rows = exactRows(COST, ERROR, 1, 4);
    EXPECT_THROW(fitModels(rows), ValueError);  // one case: no scene dependence to fit
    rows = exactRows(COST, ERROR, 3, 5);
    rows[0].costRatio = std::nan("");
    rows[1].blockRelL1 = -1;
    EXPECT_THROW(fitModels(rows), ValueError);  // one usable row left
    rows = exactRows(COST, ERROR, 3, 6);
    rows.push_back(rows[0]);
    rows.back().method = "sslpv:paper";  // one case only: left out, the others fitted
    const Models m = fitModels(rows);
    ASSERT_EQ(m.candidates.size(), 1u);
    EXPECT_EQ(m.candidates[0].method, "dipole");
    EXPECT_THROW(fitModels(rows, -1.0), ValueError);
}

TEST(PlannerModels, ReadsEvaluationCsvByColumnName) {
    // snake_case and camelCase feature columns, a quoted setting with a comma, time_ms with
    // direct_ms in place of cost_ratio, columns in any order, extra columns ignored.
    const std::string path = writeTemp(
        "lucent_models_ok.csv",
        "method,case,setting,time_ms,direct_ms,block_rel_l1,extra,optical_size,albedo,"
        "sigma_t_variation,albedo_variation,meanAbsG,eta,back_lit_fraction,curvature,"
        "thin_fraction,pixels_covered,image_pixels,lights\n"
        "sslpv:paper,sphere,\"grid 16, 16 steps\",30,10,0.25,x,100,0.9,0,0,0.8,1.3,0.5,0.2,0.4,"
        "500,1000,2\n");
    const std::vector<MeasuredRow> rows = readMeasurements(path);
    ASSERT_EQ(rows.size(), 1u);
    EXPECT_EQ(rows[0].setting, "grid 16, 16 steps");
    EXPECT_EQ(rows[0].caseName, "sphere");
    EXPECT_DOUBLE_EQ(rows[0].costRatio, 3.0);
    EXPECT_DOUBLE_EQ(rows[0].blockRelL1, 0.25);
    EXPECT_DOUBLE_EQ(rows[0].features.opticalSize, 100);
    EXPECT_DOUBLE_EQ(rows[0].features.meanAbsG, 0.8);
    EXPECT_DOUBLE_EQ(rows[0].features.pixelsCovered, 500);
    EXPECT_EQ(rows[0].features.lights, 2);
    // The CPU-time cost needs its own columns, and says which are missing.
    EXPECT_THROW(readMeasurements(path, CostMeasure::CpuTime), ValueError);
    const std::string cpu = writeTemp(
        "lucent_models_cpu.csv",
        "case,method,setting,cost_ratio,cpu_cost_ratio,block_rel_l1,feature_optical_size,"
        "feature_albedo,feature_sigma_t_variation,feature_albedo_variation,feature_mean_abs_g,"
        "feature_eta,feature_back_lit_fraction,feature_curvature,feature_thin_fraction,"
        "feature_pixels_covered\n"
        "a,dipole,8 spp,30,1.5,0.2,10,0.9,0,0,0,1.3,0,0.1,0.5,100\n");
    EXPECT_DOUBLE_EQ(readMeasurements(cpu, CostMeasure::CpuTime)[0].costRatio, 1.5);
    EXPECT_DOUBLE_EQ(readMeasurements(cpu)[0].costRatio, 30.0);
    EXPECT_DOUBLE_EQ(readMeasurements(cpu)[0].features.opticalSize, 10.0);
}

TEST(PlannerModels, CostRatiosAgainstFarApartDirectUnitsAreNamed) {
    // Rows merged from two runs: the second run's Direct render took 3x as long (a loaded
    // machine), so its method's cost ratios look 3x too cheap next to the others'.
    const std::string path = writeTemp(
        "lucent_models_units.csv",
        "case,method,setting,cpu_ms,direct_cpu_ms,block_rel_l1,feature_optical_size,"
        "feature_albedo,feature_sigma_t_variation,feature_albedo_variation,feature_mean_abs_g,"
        "feature_eta,feature_back_lit_fraction,feature_curvature,feature_thin_fraction,"
        "feature_pixels_covered\n"
        "a,direct,-,40,40,1,10,0.9,0,0,0,1.3,0,0.1,0.5,100\n"
        "a,dipole,8 spp,160,40,0.2,10,0.9,0,0,0,1.3,0,0.1,0.5,100\n"
        "a,sslpv:paper,grid 16,60,45,0.3,10,0.9,0,0,0,1.3,0,0.1,0.5,100\n"
        "a,combined,8 spp,200,120,0.1,10,0.9,0,0,0,1.3,0,0.1,0.5,100\n"
        "a,combined,32 spp,210,120,0.1,10,0.9,0,0,0,1.3,0,0.1,0.5,100\n"
        "b,dipole,8 spp,160,40,0.2,10,0.9,0,0,0,1.3,0,0.1,0.5,100\n"
        "b,combined,8 spp,200,50,0.1,10,0.9,0,0,0,1.3,0,0.1,0.5,100\n");
    const std::vector<MeasuredRow> rows = readMeasurements(path, CostMeasure::CpuTime);
    ASSERT_EQ(rows.size(), 7u);
    EXPECT_DOUBLE_EQ(rows[3].directUnitMs, 120.0);
    EXPECT_DOUBLE_EQ(rows[3].costRatio, 200.0 / 120.0);
    const std::vector<std::string> w = costUnitWarnings(rows);
    ASSERT_EQ(w.size(), 1u);  // one line for combined on case a; 45 vs 40 and case b are fine
    EXPECT_NE(w[0].find("a: combined"), std::string::npos) << w[0];
    EXPECT_NE(w[0].find("120.0 ms"), std::string::npos) << w[0];
    EXPECT_NE(w[0].find("45.0 ms"), std::string::npos) << w[0];  // the median of 40,40,45,120,120
    EXPECT_TRUE(costUnitWarnings(rows, 4.0).empty());
    // Without a unit column nothing can be said.
    for (MeasuredRow r : rows) {
        r.directUnitMs = 0.0;
        EXPECT_TRUE(costUnitWarnings({r}).empty());
    }
}

TEST(PlannerModels, CsvErrorsNameTheProblem) {
    auto message = [](const std::string& text) {
        try {
            readMeasurements(writeTemp("lucent_models_bad.csv", text));
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(message("").find("empty file"), std::string::npos);
    EXPECT_NE(message("case,method,setting,cost_ratio\n").find("block_rel_l1"), std::string::npos);
    EXPECT_NE(message("case,method,setting,cost_ratio,block_rel_l1\n").find("optical_size"),
              std::string::npos);
    const std::string header =
        "case,method,setting,cost_ratio,block_rel_l1,opticalSize,albedo,sigmaTVariation,"
        "albedoVariation,meanAbsG,eta,backLitFraction,curvature,thinFraction,pixelsCovered\n";
    EXPECT_NE(message(header + "a,b,c,1\n").find(":2: 4 fields"), std::string::npos);
    EXPECT_NE(message(header + "a,b,c,fast,0.1,1,1,0,0,0,1,0,0,0,1\n").find("'fast'"),
              std::string::npos);
    EXPECT_THROW(readMeasurements("/nonexistent/lucent.csv"), IoError);
}

TEST(PlannerModels, ModelsFileRoundTripsAndRefusesOthers) {
    Models m = fitModels(exactRows(COST, ERROR, 20, 7), 0.05);
    m.source = "test";
    const Models back = parseModels(formatModels(m), "mem");
    ASSERT_EQ(back.candidates.size(), 1u);
    EXPECT_EQ(back.source, "test");
    for (size_t k = 0; k < ERROR.size(); ++k)
        EXPECT_NEAR(back.candidates[0].error[k], m.candidates[0].error[k], 1e-6);  // 6 decimals
    const std::string text = formatModels(m);
    auto fails = [](const std::string& t, const std::string& needle) {
        try {
            parseModels(t, "f.json");
        } catch (const ValueError& e) {
            return std::string(e.what()).find(needle) != std::string::npos;
        }
        return false;
    };
    EXPECT_TRUE(fails("{", "not valid JSON"));
    EXPECT_TRUE(fails("{\"format\": \"x\"}", "not a planner models file"));
    std::string v2 = text;
    v2.replace(v2.find("\"version\": 1"), 12, "\"version\": 2");
    EXPECT_TRUE(fails(v2, "planner models version 2"));
    std::string terms = text;
    terms.replace(terms.find("\"coverage\""), 10, "\"pixels\"");
    EXPECT_TRUE(fails(terms, "terms differ"));
    std::string nan = text;
    const size_t cost = nan.find("\"cost\": [");
    const size_t first = nan.find_first_of("-0123456789", cost + 9);
    nan.replace(first, nan.find_first_of(",\n]", first) - first, "\"a\"");
    EXPECT_TRUE(fails(nan, "not a finite number"));
}

TEST(PlannerModels, ShippedModelsAreTheFitOfTheShippedSuiteFile) {
    // resources/planner/models.json must be what `lucent-cli plan --cost cpu --fit
    // resources/evaluation/suite_default.csv` makes of the CSV shipped beside it: a CSV
    // re-measured without a refit, or a models file edited by hand, fails here.
    const std::string csv =
        std::string(LUCENT_SOURCE_DIR) + "/resources/evaluation/suite_default.csv";
    const Models& shipped = defaultModels();
    const Models fitted =
        fitModels(previewRows(readMeasurements(csv, CostMeasure::CpuTime)), shipped.ridge);
    ASSERT_EQ(fitted.candidates.size(), shipped.candidates.size());
    for (size_t i = 0; i < shipped.candidates.size(); ++i) {
        const CandidateModel& a = shipped.candidates[i];
        const CandidateModel& b = fitted.candidates[i];
        const std::string name = a.method + " " + a.setting;
        ASSERT_EQ(b.method + " " + b.setting, name);
        EXPECT_EQ(a.cases, b.cases) << name;
        // The file holds 6 decimals; a rebuild with other flags may move the last bits.
        for (size_t k = 0; k < a.cost.size(); ++k)
            EXPECT_NEAR(a.cost[k], b.cost[k], 1e-5) << name << " cost term " << k;
        for (size_t k = 0; k < a.error.size(); ++k)
            EXPECT_NEAR(a.error[k], b.error[k], 1e-5) << name << " error term " << k;
        EXPECT_NEAR(a.errorLogRms, b.errorLogRms, 1e-3) << name;
    }
}

TEST(PlannerModels, ShippedSharperErrorsScoreTheShippedRenders) {
    // resources/evaluation/*_ref_floor.csv score the renders of the files beside them against
    // sharper references (`evaluate --ref-floor`), for `plan --check --judged-errors`. Each
    // setting's image against the next finer one does not depend on the reference, so equal
    // level differences say the images are the same; a file re-measured without re-scoring
    // against the sharper references fails here.
    const std::string dir = std::string(LUCENT_SOURCE_DIR) + "/resources/evaluation/";
    for (const std::string name : {"suite_default", "holdout"}) {
        const std::vector<MeasuredRow> rows =
            readMeasurements(dir + name + ".csv", CostMeasure::CpuTime);
        const std::vector<MeasuredRow> sharp =
            readMeasurements(dir + name + "_ref_floor.csv", CostMeasure::CpuTime);
        ASSERT_EQ(rows.size(), sharp.size()) << name;
        const std::vector<MeasuredRow> judged = withErrorsOf(rows, sharp);
        for (size_t i = 0; i < rows.size(); ++i) {
            const MeasuredRow& r = rows[i];
            const std::string what = name + ": " + r.caseName + " " + r.method + " " + r.setting;
            const auto s = std::find_if(sharp.begin(), sharp.end(), [&](const MeasuredRow& o) {
                return o.caseName == r.caseName && o.method == r.method && o.setting == r.setting;
            });
            ASSERT_NE(s, sharp.end()) << what;
            EXPECT_NEAR(s->blockRelL1ToFiner, r.blockRelL1ToFiner,
                        1e-4 * std::max(1.0, std::abs(r.blockRelL1ToFiner)))
                << what;
            EXPECT_LE(s->noiseFloor, r.noiseFloor) << what << ": not a sharper reference";
            EXPECT_DOUBLE_EQ(judged[i].noiseFloor, s->noiseFloor) << what;
        }
    }
}

TEST(PlannerModels, ShippedModelsMatchTheRegistry) {
    // Every shipped candidate names a registered method, variant and quality level, so a
    // renamed setting cannot silently drop out of Auto.
    const Models& m = defaultModels();
    ASSERT_FALSE(m.candidates.empty());
    EXPECT_FALSE(m.source.empty());
    for (const CandidateModel& c : m.candidates) {
        const std::string name = c.method.substr(0, c.method.find(':'));
        ASSERT_TRUE(methods::exists(name)) << c.method;
        const methods::MethodInfo& info = methods::find(name);
        if (c.method.find(':') != std::string::npos) {
            const std::string variant = c.method.substr(c.method.find(':') + 1);
            EXPECT_TRUE(std::any_of(info.variants.begin(), info.variants.end(), [&](const auto& p) {
                return p.name == variant;
            })) << c.method;
        }
        EXPECT_TRUE(std::any_of(info.quality.begin(), info.quality.end(),
                                [&](const auto& p) { return p.name == c.setting; }))
            << c.method << " " << c.setting;
        EXPECT_GE(c.cases, 2) << c.method << " " << c.setting;
    }
}

TEST(PlannerAuto, ChoiceResolvesToRegistryParametersAndSkipsWhatCannotRender) {
    Scene scene = loadScene(std::string(LUCENT_SCENES_DIR) + "/minimal.json");
    // Two synthetic candidates: dirpole (CPU: directional lights only) most accurate, dipole
    // next; the scene's light becomes a point light, so CPU-only Auto must skip dirpole.
    std::vector<MeasuredRow> rows = exactRows(COST, ERROR, 5, 8);
    for (MeasuredRow& r : rows)
        r.blockRelL1 *= 2.0;  // dipole twice dirpole's error everywhere
    std::vector<MeasuredRow> dirpole = exactRows(COST, ERROR, 5, 8);
    for (MeasuredRow& r : dirpole) {
        r.method = "dirpole";
        r.setting = "32 spp";
    }
    rows.insert(rows.end(), dirpole.begin(), dirpole.end());
    // Same features, error × 2, an unpenalised intercept: the fits differ by ln 2 in it only.
    const Models models = fitModels(rows, 0.05);
    Budget budget;
    budget.frameMs = 1e9;
    budget.directMs = 1.0;

    ASSERT_EQ(scene.lights.size(), 1u);
    scene.lights[0].type = Light::Type::Directional;
    AutoChoice c = chooseMethod(scene, models, budget, /*glAvailable=*/false);
    EXPECT_EQ(c.method, "dirpole");
    EXPECT_EQ(c.setting, "32 spp");
    ASSERT_NE(c.params.find("spp"), nullptr);
    EXPECT_EQ(*c.params.find("spp"), "32");

    scene.lights[0].type = Light::Type::Point;
    scene.lights[0].position = {0.f, 100.f, 100.f};
    c = chooseMethod(scene, models, budget, /*glAvailable=*/false);
    EXPECT_EQ(c.method, "dipole");
    EXPECT_NE(c.plan.reason.find("ignores the scene's point light"), std::string::npos)
        << c.plan.reason;
    // With GL the directional dipole's GL pass handles point lights.
    c = chooseMethod(scene, models, budget, /*glAvailable=*/true);
    EXPECT_EQ(c.method, "dirpole");

    // A models file naming what the registry lacks leaves that candidate out, with the reason.
    Models stale = models;
    stale.candidates[0].method = "photon-beams";
    stale.candidates[1].setting = "3 spp";
    stale.candidates.resize(2);
    try {
        chooseMethod(scene, stale, budget, true);
        FAIL() << "no candidate should be usable";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("not in this build's method registry"),
                  std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("no quality level '3 spp'"), std::string::npos)
            << e.what();
    }
}

TEST(PlannerAuto, SkipsSslpvGridsTheObjectIsThinnerThanHalfACellOf) {
    // SSLPV reads light only from cells at least half inside (and from them into thinner
    // parts), so an object thinner than half a cell everywhere renders black at that grid
    // (docs/methods/sslpv.md, measured: a 0.5 mm marble slab at grids 16 and 32). Auto must
    // skip those grids, say why, and keep the grids that hold a readable cell.
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / "lucent_planner_thin_slab";
    std::filesystem::create_directories(dir);
    const auto sceneWithSlab = [&](double thicknessMm) {
        const std::filesystem::path file = dir / "slab.json";
        std::ofstream(file) << R"({"version": 1,
            "mesh": {"procedural": "box", "size": [30, 30, )"
                            << thicknessMm << R"(]},
            "material": {"preset": "marble"}, "resolution": 128, "eta": 1.3,
            "lights": [{"type": "directional", "direction": [0, 0, 1], "irradiance": [1, 1, 1]}],
            "camera": {"position": [0, 0, 70], "target": [0, 0, 0], "up": [0, 1, 0],
                       "fov_y_deg": 12, "width": 64, "height": 48}})";
        return loadScene(file.string());
    };
    Budget budget;
    budget.frameMs = 1e9;
    budget.directMs = 1.0;
    const Models& models = defaultModels();
    const auto usable = [&](const AutoChoice& c, const std::string& method, int grid) {
        const std::string setting = "grid " + std::to_string(grid);
        return std::any_of(c.plan.options.begin(), c.plan.options.end(), [&](const Option& o) {
            return models.candidates[o.index].method == method &&
                   models.candidates[o.index].setting == setting;
        });
    };

    const AutoChoice thin = chooseMethod(sceneWithSlab(0.5), models, budget, true);
    for (const char* method : {"sslpv:paper", "sslpv:calibrated", "sslpv:diffusion"}) {
        EXPECT_FALSE(usable(thin, method, 16)) << method;
        EXPECT_FALSE(usable(thin, method, 32)) << method;
        EXPECT_TRUE(usable(thin, method, 64)) << method;
    }
    EXPECT_NE(thin.plan.reason.find("thinner than half a cell of grid 32"), std::string::npos)
        << thin.plan.reason;
    EXPECT_NE(thin.plan.reason.find("thinner than half a cell of grid 16"), std::string::npos)
        << thin.plan.reason;
    EXPECT_EQ(thin.plan.reason.find("of grid 64"), std::string::npos) << thin.plan.reason;

    // 2 mm is two cells of grid 32 and one of grid 16: every grid holds readable cells.
    const AutoChoice thick = chooseMethod(sceneWithSlab(2.0), models, budget, true);
    for (int grid : {16, 32, 64})
        EXPECT_TRUE(usable(thick, "sslpv:diffusion", grid)) << grid;
    EXPECT_EQ(thick.plan.reason.find("thinner than half a cell"), std::string::npos)
        << thick.plan.reason;
    std::filesystem::remove_all(dir);
}

TEST(PlannerModels, FrontCheckJudgesTheChoiceByMeasurement) {
    // Two candidates on two cases; the models predict "fast" as accurate as "slow" on case a,
    // so Auto takes fast there. Measured: on a, fast is 0.30 and slow 0.10 at 10× the cost;
    // on b the models are right.
    const auto row = [](const std::string& c, const std::string& m, double cost, double err,
                        double opticalSize) { return frontRow(c, m, cost, err, opticalSize); };
    Models models = fastAndSlow(0.1, 0.2);
    const std::vector<MeasuredRow> rows = {
        row("a", "fast", 1.0, 0.30, 10), row("a", "slow", 10.0, 0.10, 10),
        row("b", "fast", 1.2, 0.05, 100), row("b", "slow", 9.0, 0.20, 100),
        row("c", "other", 1.0, 0.01, 1)};  // no model: ignored
    const std::vector<FrontCheck> checks = checkAgainstFront(rows, models, 20.0);
    ASSERT_EQ(checks.size(), 2u);
    EXPECT_EQ(checks[0].chosen, "fast s");
    EXPECT_DOUBLE_EQ(checks[0].timeRatio, 1.0);  // fast is the cheapest at its own error
    EXPECT_EQ(checks[0].bestInBudget, "slow s");
    EXPECT_FALSE(checks[0].choseBest);
    EXPECT_TRUE(checks[1].choseBest);
    // A budget below both: the best in budget is the cheapest.
    EXPECT_EQ(checkAgainstFront(rows, models, 0.5)[0].bestInBudget, "fast s");
    // If Auto had to take slow at 0.30 measured error, fast (0.30) is as good for 1/10 the time.
    std::vector<MeasuredRow> worse = rows;
    worse[1].blockRelL1 = 0.30;
    models.candidates[0].error[0] = std::log(0.5);  // now fast is predicted worse
    const FrontCheck w = checkAgainstFront(worse, models, 20.0)[0];
    EXPECT_EQ(w.chosen, "slow s");
    EXPECT_EQ(w.cheapestAtError, "fast s");
    EXPECT_DOUBLE_EQ(w.timeRatio, 10.0);
    // The planner's tie tolerance reaches the check: fast predicted 0.25 against slow's 0.2 is
    // "equal" (and cheaper) at 30 % but not at the default 10 %.
    models.candidates[0].error[0] = std::log(0.25);
    EXPECT_EQ(checkAgainstFront(worse, models, 20.0)[0].chosen, "slow s");
    EXPECT_EQ(checkAgainstFront(worse, models, 20.0, 0.3)[0].chosen, "fast s");
    EXPECT_THROW(checkAgainstFront(rows, models, 0.0), ValueError);
    EXPECT_THROW(checkAgainstFront(rows, models, 20.0, 1.0), ValueError);
    // Planning with the measured errors (Auto measuring on its own): on case a slow's 0.10
    // beats fast's 0.30 whatever the models say; with a reference noise floor of 0.25 the two
    // cannot be told apart (0.10 · 1.1 + 0.25 ≥ 0.30) and the cheaper wins.
    models.candidates[0].error[0] = std::log(0.1);  // predicted better than slow again
    std::vector<FrontCheck> m = checkAgainstFront(rows, models, 20.0, 0.1, {}, true);
    EXPECT_EQ(m[0].chosen, "slow s");
    EXPECT_TRUE(m[0].choseBest);
    EXPECT_EQ(m[1].chosen, "fast s");
    std::vector<MeasuredRow> noisy = rows;
    for (MeasuredRow& r : noisy)
        r.noiseFloor = 0.25;
    EXPECT_EQ(checkAgainstFront(noisy, models, 20.0, 0.1, {}, true)[0].chosen, "fast s");
}

TEST(PlannerModels, CrossValidatedCheckJudgesEachCaseByModelsFittedWithoutIt) {
    // Two candidates on seven cases. On six (g = 0) fast is both cheaper and more accurate; on
    // the seventh (g = 0.9) fast is ten times as wrong. Fitted on all seven, the g slope comes
    // from that case alone and Auto takes slow there, as if it had foreseen it; with the case
    // left out no case teaches the slope, Auto takes fast and the check says so.
    const auto row = [](const std::string& c, const std::string& m, double cost, double err,
                        double g) { return frontRow(c, m, cost, err, 100.0, g); };
    std::vector<MeasuredRow> rows;
    for (int i = 0; i < 6; ++i) {
        const std::string c = "plain" + std::to_string(i);
        rows.push_back(row(c, "fast", 1.0, 0.05, 0.0));
        rows.push_back(row(c, "slow", 10.0, 0.10, 0.0));
        rows.push_back(row(c, "direct", 1.0, 0.9, 0.0));  // a baseline: never a candidate
    }
    rows.push_back(row("forward", "fast", 1.0, 0.50, 0.9));
    rows.push_back(row("forward", "slow", 10.0, 0.10, 0.9));

    const Models inSample = fitModels(previewRows(rows), 0.05);
    ASSERT_EQ(inSample.candidates.size(), 2u);  // fast and slow; direct left out
    const std::vector<FrontCheck> seen = checkAgainstFront(rows, inSample, 20.0);
    ASSERT_EQ(seen.size(), 7u);
    EXPECT_EQ(seen.back().chosen, "slow s");
    EXPECT_TRUE(seen.back().choseBest);

    const std::vector<FrontCheck> unseen = crossValidatedCheck(rows, 0.05, 20.0);
    ASSERT_EQ(unseen.size(), 7u);
    for (size_t i = 0; i < 6; ++i) {
        EXPECT_EQ(unseen[i].caseName, "plain" + std::to_string(i));
        EXPECT_EQ(unseen[i].chosen, "fast s");
        EXPECT_TRUE(unseen[i].choseBest);
    }
    EXPECT_EQ(unseen.back().caseName, "forward");
    EXPECT_EQ(unseen.back().chosen, "fast s");
    EXPECT_EQ(unseen.back().bestInBudget, "slow s");
    EXPECT_FALSE(unseen.back().choseBest);

    // One case leaves nothing to fit the others on.
    const std::vector<MeasuredRow> one(rows.end() - 2, rows.end());
    EXPECT_THROW(crossValidatedCheck(one, 0.05, 20.0), ValueError);
}

TEST(PlannerModels, ASharperReferenceCanTellApartWhatANoisyOneCannot) {
    // Auto takes slow (predicted better). Against a reference with a floor of 0.05 fast's 0.13
    // is within the floor of slow's 0.10, so the check finds fast as good for a tenth of the
    // time; the same renders against a sharper reference (floor 0.01) read 0.14 and 0.10: slow
    // is better and Auto's choice is the cheapest at its error.
    const Models models = fastAndSlow(0.3, 0.1);
    std::vector<MeasuredRow> rows = {frontRow("a", "fast", 1.0, 0.13, 10),
                                     frontRow("a", "slow", 10.0, 0.10, 10)};
    for (MeasuredRow& r : rows)
        r.noiseFloor = 0.05;
    const FrontCheck noisy = checkAgainstFront(rows, models, 20.0)[0];
    EXPECT_EQ(noisy.chosen, "slow s");
    EXPECT_DOUBLE_EQ(noisy.timeRatio, 10.0);

    std::vector<MeasuredRow> sharper = rows;
    sharper[0].blockRelL1 = 0.14;
    for (MeasuredRow& r : sharper) {
        r.noiseFloor = 0.01;
        r.costRatio = 99.0;  // not taken: the costs stay the judged rows'
    }
    const std::vector<MeasuredRow> judged = withErrorsOf(rows, sharper);
    EXPECT_DOUBLE_EQ(judged[0].blockRelL1, 0.14);
    EXPECT_DOUBLE_EQ(judged[0].noiseFloor, 0.01);
    EXPECT_DOUBLE_EQ(judged[0].costRatio, 1.0);
    const FrontCheck sharp = checkAgainstFront(judged, models, 20.0)[0];
    EXPECT_EQ(sharp.chosen, "slow s");
    EXPECT_DOUBLE_EQ(sharp.timeRatio, 1.0);
    EXPECT_TRUE(sharp.choseBest);
    // A candidate the other reference did not score is an error, not a silent keep.
    sharper.pop_back();
    EXPECT_THROW((void)withErrorsOf(rows, sharper), ValueError);
}

TEST(PlannerModels, MeasuredErrorsCanComeFromAnotherReference) {
    // Auto's own measurement has its own reference: replayed with the errors of the same
    // candidates scored against another one (`evaluate --ref-seed`), it is judged by the check's.
    const Models models = fastAndSlow(1.0, 1.0);  // the errors Auto plans by are measured
    const std::vector<MeasuredRow> judged = {frontRow("a", "fast", 1.0, 0.30, 10),
                                             frontRow("a", "slow", 10.0, 0.10, 10)};
    const FrontCheck own = checkAgainstFront(judged, models, 20.0, 0.1, {}, true)[0];
    EXPECT_EQ(own.chosen, "slow s");  // planned and judged by one reference: the best, always
    EXPECT_TRUE(own.choseBest);
    // The other reference reads fast at 0.08: Auto takes it and the check sees 0.30.
    std::vector<MeasuredRow> other = judged;
    other[0].blockRelL1 = 0.08;
    const FrontCheck replay = checkAgainstFront(judged, models, 20.0, 0.1, {}, true, &other)[0];
    EXPECT_EQ(replay.chosen, "fast s");
    EXPECT_DOUBLE_EQ(replay.chosenError, 0.30);
    EXPECT_FALSE(replay.choseBest);
    // The planning reference's floor is the tie margin: at 0.05 fast (0.08) and slow (0.10)
    // are equal there and the cheaper is taken either way; a candidate it lacks is an error.
    for (MeasuredRow& r : other)
        r.noiseFloor = 0.05;
    other[0].blockRelL1 = 0.12;
    EXPECT_EQ(checkAgainstFront(judged, models, 20.0, 0.1, {}, true, &other)[0].chosen, "fast s");
    other.pop_back();
    EXPECT_THROW(checkAgainstFront(judged, models, 20.0, 0.1, {}, true, &other), ValueError);
}
