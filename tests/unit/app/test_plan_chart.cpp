// SPDX-License-Identifier: MIT
/// @file
/// @brief The Reference dock's "Run time vs error" page (PlanChart) under Xvfb: one predicted
/// point per option of the Auto plan with the choice marked and the frame budget drawn, the
/// plan Auto would make while a fixed method runs (that method marked), and "Measure this
/// scene" on a small view with a finished reference: measured points and a measured plan; an
/// edit or closing the dock stops a measurement.
/// Auto's level check in the app (AutoLevelCheck.h): the pick renders at the level a check on a
/// worker keeps, painting keeps it and checks again once quiet, the Preferences switch turns it
/// off.
/// Also writes the user guide's screenshot of the page when LUCENT_SCREENSHOT_DIR is set.

#include "Document.h"
#include "MainWindow.h"
#include "PlanChart.h"
#include "PreviewRenderer.h"
#include "ReferencePanel.h"
#include "Viewport.h"
#include "GuiTestWaits.h"
#include "GuiTestMain.h"

#include <lucent/planner/AutoMethod.h>
#include <lucent/planner/LevelCheck.h>
#include <lucent/planner/LiveCosts.h>

#include <QAction>
#include <QApplication>
#include <QChart>
#include <QChartView>
#include <QDockWidget>
#include <QLabel>
#include <QScatterSeries>
#include <QLineSeries>
#include <QSignalSpy>
#include <QTest>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

namespace lucent::app {
namespace {

/// Renders frames until `done` or 30 frames.
template <class F>
bool renderUntil(Viewport* vp, F done) {
    for (int i = 0; i < 30 && !done(); ++i) {
        const long long f = vp->stats().frames;
        vp->update();
        if (!QTest::qWaitFor([&] { return vp->stats().frames > f; }, 20000))
            return false;
    }
    return done();
}

/// The chart's series named `objectName` (null when the chart has none).
QXYSeries* series(PlanChart* chart, const char* objectName) {
    auto* view = chart->findChild<QChartView*>(QStringLiteral("planChartView"));
    if (!view)
        return nullptr;
    for (QAbstractSeries* s : view->chart()->series())
        if (s->objectName() == QLatin1String(objectName))
            return qobject_cast<QXYSeries*>(s);
    return nullptr;
}

int count(PlanChart* chart, const char* objectName) {
    QXYSeries* s = series(chart, objectName);
    return s ? int(s->count()) : 0;
}

/// The main window at 1366×708 (a 1366×768 screen less its panel) with the Reference dock's
/// chart page shown.
std::unique_ptr<MainWindow> windowOnChart() {
    auto w = std::make_unique<MainWindow>(/*restoreSettings=*/false);
    w->resize(1366, 708);
    w->show();
    EXPECT_TRUE(QTest::qWaitForWindowExposed(w.get(), test::kWindowWaitMs));
    if (auto* d = w->findChild<QDockWidget*>(QStringLiteral("dockReference")))
        d->raise();
    w->referencePanel()->showPage(1);
    return w;
}

}  // namespace

TEST(AppPlanChart, OnePointPerOptionTheChoiceMarkedAndTheBudgetDrawn) {
    auto w = windowOnChart();
    Viewport* vp = w->viewport();
    PlanChart* chart = w->referencePanel()->planChart();
    ASSERT_NE(chart, nullptr);
    ASSERT_EQ(vp->renderSettings().method, AUTO_METHOD);
    // Auto plans once its Direct frames are timed; pinned: a plan that does not hang on load.
    vp->previewRenderer().pinAutoDirectMs(planner::defaultLiveCosts().directMs);
    ASSERT_TRUE(renderUntil(vp, [&] { return vp->previewRenderer().autoChoice() != nullptr; }));
    chart->refreshPlan();
    const planner::AutoChoice choice = *vp->previewRenderer().autoChoice();
    const planner::Plan& plan = choice.plan;
    ASSERT_TRUE(plan.valid);
    ASSERT_GE(plan.options.size(), 2u);
    EXPECT_EQ(chart->predictedPoints(), int(plan.options.size()));
    EXPECT_EQ(count(chart, "predictedSeries"), int(plan.options.size()));
    // The chosen one, once, at its predicted time and error (in %).
    ASSERT_EQ(count(chart, "chosenSeries"), 1);
    const QPointF c = series(chart, "chosenSeries")->at(0);
    EXPECT_DOUBLE_EQ(c.x(), plan.chosen.ms);
    EXPECT_DOUBLE_EQ(c.y(), 100.0 * plan.chosen.error);
    const planner::CandidateModel& m = PreviewRenderer::liveModels().candidates[plan.choice];
    EXPECT_EQ(chart->chosenLabel().toStdString(), m.method + " " + m.setting);
    // Every option is a point.
    QXYSeries* predicted = series(chart, "predictedSeries");
    for (size_t i = 0; i < plan.options.size(); ++i) {
        EXPECT_DOUBLE_EQ(predicted->at(qsizetype(i)).x(), plan.options[i].ms);
        EXPECT_DOUBLE_EQ(predicted->at(qsizetype(i)).y(), 100.0 * plan.options[i].error);
    }
    // The budget: a vertical line at the preview's frame budget.
    QXYSeries* budget = series(chart, "budgetSeries");
    ASSERT_NE(budget, nullptr);
    ASSERT_EQ(budget->count(), 2);
    EXPECT_DOUBLE_EQ(budget->at(0).x(), planner::Budget().frameMs);
    EXPECT_DOUBLE_EQ(budget->at(1).x(), planner::Budget().frameMs);
    EXPECT_EQ(count(chart, "currentMethodSeries"), 0) << "Auto runs: no fixed method to mark";

    // A fixed method: the plan Auto would make, the method's candidates marked.
    RenderSettings rs = vp->renderSettings();
    rs.method = "dirpole";
    vp->setRenderSettings(rs);
    ASSERT_TRUE(renderUntil(vp, [&] { return vp->stats().preview.method == "dirpole"; }));
    chart->refreshPlan();
    EXPECT_GE(chart->predictedPoints(), 2);
    EXPECT_EQ(count(chart, "chosenSeries"), 1);
    int dirpoleOptions = 0;
    for (const planner::CandidateModel& cm : PreviewRenderer::liveModels().candidates)
        dirpoleOptions += cm.method == "dirpole";
    ASSERT_GT(dirpoleOptions, 0) << "the shipped live costs have a dirpole candidate";
    EXPECT_EQ(count(chart, "currentMethodSeries"), dirpoleOptions);
}

TEST(AppPlanChart, MeasuringASmallSceneGivesMeasuredPointsAndAPlan) {
    auto w = windowOnChart();
    Viewport* vp = w->viewport();
    ReferencePanel* ref = w->referencePanel();
    PlanChart* chart = ref->planChart();
    vp->previewRenderer().pinAutoDirectMs(planner::defaultLiveCosts().directMs);
    ASSERT_TRUE(renderUntil(vp, [&] { return vp->previewRenderer().autoChoice() != nullptr; }));
    chart->refreshPlan();
    ASSERT_GE(chart->predictedPoints(), 2);
    // A finished reference of this view, small: the error is measured against it.
    ref->setParameters(/*width=*/48, /*spp=*/8);
    ref->start();
    ASSERT_TRUE(QTest::qWaitFor([&] { return !ref->isRunning(); }, 120000));
    ASSERT_TRUE(ref->hasFinishedReferenceOfView());

    QSignalSpy finished(chart, &PlanChart::measurementFinished);
    chart->measure();
    EXPECT_TRUE(chart->isMeasuring());
    // Off the UI thread: the viewport keeps drawing while the candidates render.
    const long long f = vp->stats().frames;
    vp->update();
    EXPECT_TRUE(QTest::qWaitFor([&] { return vp->stats().frames > f; }, 10000));
    ASSERT_TRUE(QTest::qWaitFor([&] { return !chart->isMeasuring(); }, 240000));
    EXPECT_EQ(finished.count(), 1);
    auto* line = chart->findChild<QLabel*>(QStringLiteral("planChartMeasured"));
    ASSERT_NE(line, nullptr);
    // Every candidate measured (each one is a GL preview method), with its error.
    EXPECT_EQ(chart->measuredPoints(), chart->predictedPoints()) << line->text().toStdString();
    EXPECT_EQ(count(chart, "measuredSeries"), chart->measuredPoints());
    EXPECT_EQ(count(chart, "measuredChosenSeries"), 1);
    EXPECT_FALSE(chart->measuredPlanReason().isEmpty());
    EXPECT_TRUE(line->text().contains(QStringLiteral("Measured on this scene")))
        << line->text().toStdString();
    for (int i = 0; i < count(chart, "measuredSeries"); ++i) {
        const QPointF p = series(chart, "measuredSeries")->at(i);
        EXPECT_GT(p.x(), 0.0);
        EXPECT_GT(p.y(), 0.0);
    }
    // The measured errors update Auto's live plan (its costs stay the live ones): the next
    // frames plan with them, so the chosen option's error is one of the measured errors, and
    // the reason says so.
    ASSERT_TRUE(renderUntil(vp, [&] { return vp->previewRenderer().usesMeasuredModels(); }));
    const planner::AutoChoice* measuredLive = vp->previewRenderer().autoChoice();
    ASSERT_NE(measuredLive, nullptr);
    bool chosenErrorWasMeasured = false;
    for (int i = 0; i < count(chart, "measuredSeries"); ++i)
        chosenErrorWasMeasured |= std::abs(series(chart, "measuredSeries")->at(i).y() -
                                           100.0 * measuredLive->plan.chosen.error) <=
                                  1e-9 * series(chart, "measuredSeries")->at(i).y();
    EXPECT_TRUE(chosenErrorWasMeasured) << measuredLive->plan.reason;
    EXPECT_EQ(vp->stats().preview.autoReason.rfind("errors measured on this view: ", 0), 0u)
        << vp->stats().preview.autoReason;
    EXPECT_TRUE(line->text().contains(QStringLiteral("Auto now plans with these errors")))
        << line->text().toStdString();

    // An edit makes the measurement stale: a new one is cancelled by it.
    chart->measure();
    ASSERT_TRUE(chart->isMeasuring());
    w->document()->setEta(w->document()->scene().eta + 0.05f);
    ASSERT_TRUE(QTest::qWaitFor([&] { return !chart->isMeasuring(); }, 120000));
    EXPECT_EQ(chart->measuredPoints(), 0);
    EXPECT_TRUE(line->text().contains(QStringLiteral("stopped"))) << line->text().toStdString();
    // The edit also ends Auto's use of the measured errors: it plans with its models again.
    EXPECT_TRUE(renderUntil(vp, [&] {
        return vp->previewRenderer().autoChoice() && !vp->previewRenderer().usesMeasuredModels();
    }));

    // The other page of the dock shown: it goes on; the dock closed: it stops.
    chart->measure();
    ASSERT_TRUE(chart->isMeasuring());
    ref->showPage(0);
    EXPECT_TRUE(chart->isMeasuring());
    auto* dock = w->findChild<QDockWidget*>(QStringLiteral("dockReference"));
    ASSERT_NE(dock, nullptr);
    dock->close();
    ASSERT_TRUE(QTest::qWaitFor([&] { return !chart->isMeasuring(); }, 120000));
    EXPECT_EQ(chart->measuredPoints(), 0);
    EXPECT_TRUE(line->text().contains(QStringLiteral("stopped"))) << line->text().toStdString();

    const QString dir = qEnvironmentVariable("LUCENT_SCREENSHOT_DIR");
    if (!dir.isEmpty()) {  // the user guide's picture: measure again, then grab the window
        dock->show();
        dock->raise();
        ref->showPage(1);
        chart->measure();
        ASSERT_TRUE(QTest::qWaitFor([&] { return !chart->isMeasuring(); }, 240000));
        renderUntil(vp, [] { return false; });
        ASSERT_TRUE(vp->grabWithFrame(w.get()).save(dir + QStringLiteral("/app-plan-chart.png")));
    }
}

TEST(AppAutoLevelCheck, ThePickRendersAtTheLevelTheCheckKeepsAndPaintingRechecks) {
    auto w = windowOnChart();
    Viewport* vp = w->viewport();
    PreviewRenderer& preview = vp->previewRenderer();
    AutoLevelChecker& checker = vp->levelChecker();
    EXPECT_EQ(checker.tolerance().absolute, planner::LevelTolerance::visibleOnly().absolute);
    EXPECT_EQ(checker.tolerance().relative, 0.0) << "the live preview is judged by eye";
    // A tolerance every difference is within (summed block errors of 10): the check keeps the
    // cheapest level.
    checker.setTolerance({10.0, 0.0});
    // A Direct frame of 1 ms: every candidate fits the 50 ms budget and Auto takes the least
    // predicted error, an SSLPV grid, which has cheaper levels (at the table's own unit the
    // pick can be a candidate measured live at one level only, the dipoles' 128 spp).
    preview.pinAutoDirectMs(1.0);
    ASSERT_TRUE(renderUntil(vp, [&] { return preview.autoPlannedChoice() != nullptr; }));
    const planner::AutoChoice planned = *preview.autoPlannedChoice();
    const std::vector<std::string> levels =
        planner::modelLevels(PreviewRenderer::liveModels(), planned.candidate());
    ASSERT_GE(levels.size(), 2u) << planned.plan.reason;
    ASSERT_NE(planned.setting, levels.front())
        << "the default scene's pick has a cheaper level: " << planned.plan.reason;

    // Off the UI thread: the viewport keeps drawing while the levels render.
    ASSERT_TRUE(QTest::qWaitFor([&] { return checker.checksDone() >= 1; }, 240000));
    EXPECT_NE(checker.lastNote().indexOf(QString::fromStdString(levels.front() + ": ")), -1)
        << checker.lastNote().toStdString();
    const std::string kept = planned.candidate() + " " + levels.front();
    ASSERT_TRUE(renderUntil(vp, [&] { return vp->stats().preview.autoChoice == kept; }))
        << preview.autoChoice()->plan.reason;
    EXPECT_EQ(preview.autoChoice()->setting, levels.front());
    EXPECT_EQ(preview.autoPlannedChoice()->setting, planned.setting);  // the models' pick kept
    EXPECT_EQ(vp->stats().preview.autoReason.rfind(kept + " by the level check: ", 0), 0u)
        << vp->stats().preview.autoReason;

    // Painting keeps the decision (no switch mid-stroke) and, once quiet, checks again.
    const int before = checker.checksDone();
    const QPointF c(vp->width() / 2.0, vp->height() / 2.0);
    ASSERT_EQ(vp->strokeBetween(c - QPointF(20, 0), c + QPointF(20, 0)), 1);
    ASSERT_TRUE(renderUntil(vp, [&] { return vp->stats().frames > 0; }));
    EXPECT_EQ(preview.autoChoice()->setting, levels.front());
    ASSERT_TRUE(QTest::qWaitFor([&] { return checker.checksDone() > before; }, 240000));

    // A tolerance nothing is within: the next check (after an edit) keeps the pick.
    checker.setTolerance({1e-9, 0.0});
    w->document()->setEta(w->document()->scene().eta + 0.01f);
    const int edited = checker.checksDone();
    ASSERT_TRUE(QTest::qWaitFor([&] { return checker.checksDone() > edited; }, 240000));
    ASSERT_TRUE(renderUntil(vp, [&] {
        return preview.autoChoice()->setting == preview.autoPlannedChoice()->setting;
    })) << preview.autoChoice()->plan.reason;
    EXPECT_NE(checker.lastNote().indexOf(QStringLiteral(" kept: ")), -1)
        << checker.lastNote().toStdString();

    // Edit ▸ Preferences ▸ Auto: Check Quality Levels off: the decisions go, the pick renders
    // at its own level, and edits start no check.
    checker.setTolerance({10.0, 0.0});
    w->document()->setEta(w->document()->scene().eta + 0.01f);
    const int again = checker.checksDone();
    ASSERT_TRUE(QTest::qWaitFor([&] { return checker.checksDone() > again; }, 240000));
    ASSERT_TRUE(renderUntil(vp, [&] { return vp->stats().preview.autoChoice == kept; }));
    auto* toggle = w->findChild<QAction*>(QStringLiteral("actionAutoLevelCheck"));
    ASSERT_NE(toggle, nullptr);
    ASSERT_TRUE(toggle->isChecked());
    toggle->trigger();
    EXPECT_FALSE(checker.isEnabled());
    ASSERT_TRUE(renderUntil(vp, [&] {
        return vp->stats().preview.autoChoice == planned.candidate() + " " + planned.setting;
    })) << vp->stats().preview.autoChoice;
    const int off = checker.checksDone();
    w->document()->setEta(w->document()->scene().eta + 0.01f);
    QTest::qWait(int(AutoLevelChecker::RECHECK_IDLE_MS) + 500);
    EXPECT_FALSE(checker.running());
    EXPECT_EQ(checker.checksDone(), off);
    EXPECT_EQ(preview.autoChoice()->setting, preview.autoPlannedChoice()->setting);
}

// Auto measuring the scene on its own (AutoMeasure.h): off without settings (tests, scripted
// runs); switched on, it measures once the scene has been shown quietly, and Auto then plans
// with the measured errors: on the default scene it leaves the models' pick for the candidate
// the measurement puts first. The measured errors hold while the artist paints (the pick stays
// a measured one), a pause measures again, and switching it off gives Auto its models back.
TEST(AppAutoMeasure, AutoPlansWithTheErrorsItMeasuredAndKeepsThemWhilePainting) {
    auto w = windowOnChart();
    Viewport* vp = w->viewport();
    PreviewRenderer& preview = vp->previewRenderer();
    AutoMeasurer& measurer = vp->autoMeasurer();
    auto* toggle = w->findChild<QAction*>(QStringLiteral("actionAutoMeasure"));
    ASSERT_NE(toggle, nullptr);
    EXPECT_FALSE(toggle->isChecked()) << "off without settings";
    EXPECT_FALSE(measurer.isEnabled());
    preview.pinAutoDirectMs(planner::defaultLiveCosts().directMs);
    ASSERT_TRUE(renderUntil(vp, [&] { return preview.autoPlannedChoice() != nullptr; }));
    const planner::AutoChoice modelsPick = *preview.autoPlannedChoice();
    EXPECT_FALSE(preview.usesMeasuredModels());

    measurer.setQuietMs(200);
    toggle->trigger();
    EXPECT_TRUE(measurer.isEnabled());
    // The live-cost calibration pauses refinement: a measurement in progress stops unapplied,
    // and runs again once resumed.
    ASSERT_TRUE(QTest::qWaitFor([&] { return measurer.running(); }, 20000));
    vp->setRefinementPaused(true);
    ASSERT_TRUE(QTest::qWaitFor([&] { return !measurer.running(); }, 240000));
    EXPECT_FALSE(preview.hasMeasuredModels());
    QTest::qWait(400);
    EXPECT_FALSE(measurer.running()) << "nothing starts while paused";
    vp->setRefinementPaused(false);
    const int stopped = measurer.measurementsDone();
    ASSERT_TRUE(QTest::qWaitFor([&] { return measurer.measurementsDone() > stopped; }, 240000));
    EXPECT_NE(measurer.lastNote().indexOf(QStringLiteral("against the exact reference (64×")), -1)
        << measurer.lastNote().toStdString();
    ASSERT_TRUE(renderUntil(vp, [&] { return preview.usesMeasuredModels(); }));
    EXPECT_EQ(vp->stats().preview.autoReason.rfind("errors measured on this scene: ", 0), 0u)
        << vp->stats().preview.autoReason;
    // The measured plan's pick: within the planner's tie rule (10 % plus the reference's noise)
    // of the least measured error among the candidates that fit.
    const planner::Plan& measuredPlan = preview.autoPlannedChoice()->plan;
    double least = INFINITY;
    for (const planner::Option& o : measuredPlan.options)
        if (o.fits)
            least = std::min(least, o.error);
    EXPECT_GT(measurer.lastReferenceNoise(), 0.0);
    EXPECT_LE(measuredPlan.chosen.error, least * 1.1 + measurer.lastReferenceNoise() + 1e-12);
    std::printf("models' pick: %s; measured plan: %s\n", modelsPick.plan.reason.c_str(),
                measuredPlan.reason.c_str());

    // Painting keeps the measured errors (the preview does not fall back to the models' pick
    // mid-stroke), and the pause after it measures again.
    const int before = measurer.measurementsDone();
    const QPointF c(vp->width() / 2.0, vp->height() / 2.0);
    ASSERT_EQ(vp->strokeBetween(c - QPointF(20, 0), c + QPointF(20, 0)), 1);
    ASSERT_TRUE(renderUntil(vp, [&] { return vp->stats().frames > 0; }));
    EXPECT_TRUE(preview.usesMeasuredModels());
    ASSERT_TRUE(QTest::qWaitFor([&] { return measurer.measurementsDone() > before; }, 240000));
    ASSERT_TRUE(renderUntil(vp, [&] { return preview.usesMeasuredModels(); }));

    // Off: the models again.
    toggle->trigger();
    EXPECT_FALSE(measurer.isEnabled());
    ASSERT_TRUE(renderUntil(vp, [&] { return !preview.usesMeasuredModels(); }));
    EXPECT_FALSE(preview.hasMeasuredModels());
    const int off = measurer.measurementsDone();
    w->document()->setEta(w->document()->scene().eta + 0.01f);
    QTest::qWait(500);
    EXPECT_FALSE(measurer.running());
    EXPECT_EQ(measurer.measurementsDone(), off);
}

}  // namespace lucent::app

int main(int argc, char** argv) {
    return lucent::app::test::runGuiTests(argc, argv);
}
