// SPDX-License-Identifier: MIT
/// @file
/// @brief Calibrating the live costs on this machine (planner/LiveCalibration.h) and where the
/// calibration lives (planner/LiveCosts.h: userLiveCostsPath, loadLiveCosts): a tiny headless
/// calibration gives a finite positive ratio per candidate with every stroke counted and
/// round-trips through the file format; a cancel stops it; the path rule follows the
/// environment; a calibration file is used when it covers the shipped candidates, and a bad
/// one falls back to the shipped table with a warning.

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/planner/LiveCalibration.h>
#include <lucent/planner/LiveCosts.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

using namespace lucent;
using namespace lucent::planner;

namespace {

/// Two candidates of different kinds (a volume propagation and an image-space gather) on a
/// viewport small enough for a unit test: the stroke and the frames as at 640×360, fewer pixels.
LiveCalibrationOptions tinyCalibration() {
    LiveCalibrationOptions o;
    o.viewportWidth = 96;
    o.viewportHeight = 64;
    o.strokes = 3;
    o.warmupStrokes = 1;
    o.idleFrames = 1;
    o.rounds = 2;
    o.candidates = {{"sslpv:paper", "grid 16", 0.0}, {"dirpole", "8 spp", 0.0}};
    o.command = "test_planner";
    return o;
}

#define REQUIRE_HEADLESS_GL()                                          \
    do {                                                               \
        std::string why;                                               \
        if (!gpu::GlContext::isHeadlessAvailable(&why))                \
            GTEST_SKIP() << "no headless OpenGL 4.5 context: " << why; \
    } while (0)

/// Sets (or, with nullopt, unsets) an environment variable for the scope, restoring it after.
class ScopedEnv {
public:
    ScopedEnv(const char* name, const std::optional<std::string>& value) : m_name(name) {
        if (const char* old = std::getenv(name))
            m_old = old;
        if (value)
            setenv(name, value->c_str(), 1);
        else
            unsetenv(name);
    }
    ~ScopedEnv() {
        if (m_old)
            setenv(m_name, m_old->c_str(), 1);
        else
            unsetenv(m_name);
    }
    ScopedEnv(const ScopedEnv&) = delete;
    ScopedEnv& operator=(const ScopedEnv&) = delete;

private:
    const char* m_name;
    std::optional<std::string> m_old;
};

std::filesystem::path freshDir(const std::string& name) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

/// The shipped table with every ratio multiplied by `factor`, in reverse order.
LiveCosts scaledShipped(double factor) {
    LiveCosts c = defaultLiveCosts();
    c.source = "test calibration";
    c.date = "2026-12-03";
    c.renderer = "Test GPU (fake, 1 bit)";
    for (LiveCost& e : c.entries)
        e.strokeRatio *= factor;
    std::reverse(c.entries.begin(), c.entries.end());
    return c;
}

}  // namespace

TEST(LiveCalibration, TinyViewportGivesFinitePositiveRatiosThatRoundTrip) {
    REQUIRE_HEADLESS_GL();
    const LiveCalibrationOptions o = tinyCalibration();
    int reports = 0, lastDone = -1, total = 0;
    LiveCalibrationOptions withProgress = o;
    withProgress.progress = [&](const LiveCalibrationProgress& p) {
        ++reports;
        EXPECT_GE(p.done, lastDone);  // never goes back
        lastDone = p.done;
        total = p.total;
    };
    const LiveCalibration c = calibrateLiveCosts(withProgress);
    ASSERT_FALSE(c.cancelled);
    EXPECT_EQ(total, o.rounds * 2 * 2);  // rounds × candidates × (Direct + candidate)
    EXPECT_EQ(lastDone, total);
    EXPECT_EQ(reports, total + 1);  // before every run, and once at the end
    ASSERT_EQ(c.rows.size(), 2u);
    ASSERT_EQ(c.costs.entries.size(), 2u);
    for (size_t i = 0; i < 2; ++i) {
        const LiveCalibrationRow& r = c.rows[i];
        SCOPED_TRACE(r.cost.method + " " + r.cost.setting);
        EXPECT_EQ(r.cost.method, o.candidates[i].method);  // in the order asked
        EXPECT_EQ(r.cost.setting, o.candidates[i].setting);
        EXPECT_EQ(r.strokesTimed, o.strokes * o.rounds);  // warm-up strokes not counted
        ASSERT_EQ(r.roundRatios.size(), size_t(o.rounds));
        EXPECT_TRUE(std::isfinite(r.cost.strokeRatio) && r.cost.strokeRatio > 0)
            << r.cost.strokeRatio;
        EXPECT_GT(r.strokeMs, 0.0);
        EXPECT_GT(r.directMs, 0.0);
        // The ratio is the median over rounds: with two rounds, their mean.
        EXPECT_NEAR(r.cost.strokeRatio, 0.5 * (r.roundRatios[0] + r.roundRatios[1]),
                    1e-12 * r.cost.strokeRatio);
        EXPECT_DOUBLE_EQ(c.costs.entries[i].strokeRatio, r.cost.strokeRatio);
    }
    EXPECT_GT(c.costs.directMs, 0.0);
    EXPECT_FALSE(c.costs.renderer.empty());
    EXPECT_GT(c.costs.cpuThreads, 0);
    EXPECT_EQ(c.costs.date.size(), 10u) << c.costs.date;  // YYYY-MM-DD
    EXPECT_NE(c.costs.source.find("test_planner"), std::string::npos) << c.costs.source;
    EXPECT_NE(c.costs.source.find("96x64"), std::string::npos) << c.costs.source;
    EXPECT_NE(c.costs.source.find(c.costs.renderer), std::string::npos) << c.costs.source;

    // The file: what parse reads back is what was measured, to the format's rounding
    // (ratios to 10⁻³, the unit to 10⁻² ms).
    const LiveCosts back = parseLiveCosts(formatLiveCosts(c.costs), "calibration");
    EXPECT_EQ(back.source, c.costs.source);
    EXPECT_EQ(back.date, c.costs.date);
    EXPECT_EQ(back.renderer, c.costs.renderer);
    EXPECT_EQ(back.cpuThreads, c.costs.cpuThreads);
    EXPECT_NEAR(back.directMs, c.costs.directMs, 0.005 + 1e-12);
    ASSERT_EQ(back.entries.size(), 2u);
    for (size_t i = 0; i < 2; ++i) {
        EXPECT_EQ(back.entries[i].method, c.costs.entries[i].method);
        EXPECT_EQ(back.entries[i].setting, c.costs.entries[i].setting);
        EXPECT_NEAR(back.entries[i].strokeRatio, c.costs.entries[i].strokeRatio, 0.0005 + 1e-12);
    }
}

TEST(LiveCalibration, CancelStopsAndReturnsNoTable) {
    REQUIRE_HEADLESS_GL();
    // Cancelled before it starts: nothing is measured.
    std::atomic<bool> cancel{true};
    LiveCalibrationOptions o = tinyCalibration();
    o.cancel = &cancel;
    LiveCalibration c = calibrateLiveCosts(o);
    EXPECT_TRUE(c.cancelled);
    EXPECT_TRUE(c.costs.entries.empty());
    EXPECT_TRUE(c.rows.empty());

    // Cancelled after the first run (the first Direct run): it stops before the next frame.
    cancel = false;
    int runsDone = 0;
    o.progress = [&](const LiveCalibrationProgress& p) {
        runsDone = p.done;
        if (p.done >= 1)
            cancel = true;
    };
    c = calibrateLiveCosts(o);
    EXPECT_TRUE(c.cancelled);
    EXPECT_TRUE(c.costs.entries.empty());
    EXPECT_EQ(runsDone, 1);
}

TEST(LiveCalibration, RefusesBadOptionsBeforeAnyRendering) {
    LiveCalibrationOptions o = tinyCalibration();
    o.candidates = {{"no-such-method", "grid 16", 0.0}};
    EXPECT_THROW(calibrateLiveCosts(o), ValueError);
    o = tinyCalibration();
    o.candidates = {{"sslpv:paper", "grid 17", 0.0}};
    EXPECT_THROW(calibrateLiveCosts(o), ValueError);
    o = tinyCalibration();
    o.strokes = 0;
    EXPECT_THROW(calibrateLiveCosts(o), ValueError);
    o = tinyCalibration();
    o.viewportWidth = 8;
    EXPECT_THROW(calibrateLiveCosts(o), ValueError);
    o = tinyCalibration();
    o.resolutionScale = 0.f;
    EXPECT_THROW(calibrateLiveCosts(o), ValueError);
}

TEST(LiveCostsLocation, FollowsTheEnvironment) {
    ScopedEnv given(LIVE_COSTS_ENV, std::nullopt);
    {
        ScopedEnv xdg("XDG_CONFIG_HOME", "/tmp/xdg-config");
        ScopedEnv home("HOME", "/home/artist");
        EXPECT_EQ(userLiveCostsPath(), "/tmp/xdg-config/lucent/live_costs.json");
    }
    {
        ScopedEnv xdg("XDG_CONFIG_HOME", std::nullopt);
        ScopedEnv home("HOME", "/home/artist");
        EXPECT_EQ(userLiveCostsPath(), "/home/artist/.config/lucent/live_costs.json");
    }
    {
        // A relative XDG_CONFIG_HOME is invalid (XDG Base Directory Specification): ignored.
        ScopedEnv xdg("XDG_CONFIG_HOME", "relative/config");
        ScopedEnv home("HOME", "/home/artist");
        EXPECT_EQ(userLiveCostsPath(), "/home/artist/.config/lucent/live_costs.json");
    }
    {
        ScopedEnv xdg("XDG_CONFIG_HOME", "");
        ScopedEnv home("HOME", std::nullopt);
        EXPECT_EQ(userLiveCostsPath(), "");
    }
    ScopedEnv override(LIVE_COSTS_ENV, "/elsewhere/costs.json");
    ScopedEnv xdg("XDG_CONFIG_HOME", "/tmp/xdg-config");
    EXPECT_EQ(userLiveCostsPath(), "/elsewhere/costs.json");
}

TEST(LiveCostsLocation, UsesACalibrationThatCoversTheShippedCandidates) {
    const std::filesystem::path dir = freshDir("lucent_test_live_costs_location");
    const std::string path = (dir / "lucent" / "live_costs.json").string();

    // No file: the shipped table, and nothing to warn about.
    LiveCostsInUse inUse = loadLiveCosts(path);
    EXPECT_FALSE(inUse.calibrated);
    EXPECT_TRUE(inUse.warning.empty()) << inUse.warning;
    EXPECT_EQ(inUse.costs.entries.size(), defaultLiveCosts().entries.size());
    // The shipped file's own measurement date (it is re-measured when a method's live cost moves).
    EXPECT_EQ(describeLiveCosts(inUse),
              "shipped (llvmpipe, 2 threads, " + defaultLiveCosts().date + ")");
    EXPECT_FALSE(defaultLiveCosts().date.empty());

    // A calibration (saved into a folder that does not exist yet), in another order: used, in
    // the shipped order, with its own ratios.
    saveLiveCosts(scaledShipped(2.0), path);
    inUse = loadLiveCosts(path);
    EXPECT_TRUE(inUse.calibrated);
    EXPECT_TRUE(inUse.warning.empty()) << inUse.warning;
    ASSERT_EQ(inUse.costs.entries.size(), defaultLiveCosts().entries.size());
    for (size_t i = 0; i < inUse.costs.entries.size(); ++i) {
        const LiveCost& shipped = defaultLiveCosts().entries[i];
        EXPECT_EQ(inUse.costs.entries[i].method, shipped.method);
        EXPECT_EQ(inUse.costs.entries[i].setting, shipped.setting);
        EXPECT_NEAR(inUse.costs.entries[i].strokeRatio, 2.0 * shipped.strokeRatio, 1e-3);
    }
    EXPECT_EQ(describeLiveCosts(inUse), "calibrated on this machine 2026-12-03 (Test GPU)");
    // liveModels plans with the calibrated ratios.
    const Models live = liveModels(defaultModels(), inUse.costs);
    ASSERT_FALSE(live.candidates.empty());
    EXPECT_NEAR(std::exp(live.candidates[0].cost[0]), inUse.costs.entries[0].strokeRatio, 1e-9);

    // A file without one of the shipped candidates (another version): shipped, with a warning.
    LiveCosts partial = scaledShipped(2.0);
    partial.entries.pop_back();  // the shipped table's first entry (reversed)
    saveLiveCosts(partial, path);
    inUse = loadLiveCosts(path);
    EXPECT_FALSE(inUse.calibrated);
    EXPECT_NE(inUse.warning.find(defaultLiveCosts().entries[0].method), std::string::npos)
        << inUse.warning;
    EXPECT_NE(inUse.warning.find(path), std::string::npos) << inUse.warning;
    EXPECT_DOUBLE_EQ(inUse.costs.entries[0].strokeRatio, defaultLiveCosts().entries[0].strokeRatio);

    // A malformed file: shipped, with a warning naming the file; never an exception.
    writeFileAtomically(path, std::string("{\"format\": \"lucent-planner-live-costs\", "));
    EXPECT_NO_THROW(inUse = loadLiveCosts(path));
    EXPECT_FALSE(inUse.calibrated);
    EXPECT_NE(inUse.warning.find(path), std::string::npos) << inUse.warning;
    EXPECT_NE(inUse.warning.find("calibrate again"), std::string::npos) << inUse.warning;
    EXPECT_EQ(inUse.costs.entries.size(), defaultLiveCosts().entries.size());

    // A ratio that is not a positive number: the same.
    writeFileAtomically(path, formatLiveCosts(scaledShipped(2.0)));
    std::string text = formatLiveCosts(scaledShipped(2.0));
    text.replace(text.find("\"stroke_ratio\": ") + 16, 1, "-");
    writeFileAtomically(path, text);
    inUse = loadLiveCosts(path);
    EXPECT_FALSE(inUse.calibrated);
    EXPECT_NE(inUse.warning.find("stroke_ratio"), std::string::npos) << inUse.warning;
    std::filesystem::remove_all(dir);
}
