// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The Reference dock's "Run time vs error" page: every candidate of the Auto plan for
/// the current scene as a predicted point (frame time, block error), Auto's choice marked, the
/// frame budget as a vertical line; and "Measure this scene": each candidate rendered on the
/// view through the engine (planner::measureCandidates) on a worker thread, its measured point
/// beside the prediction, and the plan the measured numbers give. Qt Charts stays in the .cpp.

#include <lucent/core/Types.h>

#include <QWidget>

#include <atomic>
#include <memory>
#include <string>
#include <vector>

class QLabel;
class QPushButton;
class QThread;

namespace lucent::planner {
struct AutoChoice;
struct SceneMeasurement;
}  // namespace lucent::planner

namespace lucent::app {

class Document;
class ReferencePanel;
class Viewport;

class PlanChart : public QWidget {
    Q_OBJECT
public:
    /// `reference`: the dock, for the frozen view and its finished reference.
    PlanChart(Document* doc, Viewport* viewport, ReferencePanel* reference,
              QWidget* parent = nullptr);
    ~PlanChart() override;

    /// Plans again and redraws the predicted points (called when the Auto plan changes).
    void refreshPlan();
    /// Starts measuring every candidate of the plan on the current view (no-op while one runs).
    void measure();
    /// Stops a running measurement after its current render; returns at once.
    void cancelMeasurement();
    [[nodiscard]] bool isMeasuring() const { return m_thread != nullptr; }

    /// What the chart shows, for tests: predicted points, the chosen one's label ("method
    /// setting"), measured points, the measured plan's reason ("" before a measurement).
    [[nodiscard]] int predictedPoints() const { return int(m_predicted.size()); }
    [[nodiscard]] QString chosenLabel() const;
    [[nodiscard]] int measuredPoints() const { return int(m_measured.size()); }
    [[nodiscard]] QString measuredPlanReason() const { return m_measuredReason; }

    /// One point.
    struct Point {
        QString label;  ///< "method setting"
        double ms = 0.0;
        double error = 0.0;  ///< block relative L1 (fraction)
        bool chosen = false;
        bool currentMethod = false;  ///< the viewport's fixed method
    };

Q_SIGNALS:
    /// A measurement ended (finished, failed or cancelled); measuredPoints() says what it got.
    void measurementFinished();

protected:
    /// Stops a measurement when the Reference dock hides (closed, or behind another dock).
    bool eventFilter(QObject* watched, QEvent* event) override;
    /// Plans when shown if the scene, view or method changed while hidden.
    void showEvent(QShowEvent* event) override;

private:
    void redraw();
    /// Fills m_measured and the measured line from a finished measurement.
    void showMeasurement(const planner::SceneMeasurement& result,
                         const planner::AutoChoice& measuredChoice, bool withReference,
                         double directMs);
    Document* m_doc;
    Viewport* m_viewport;
    ReferencePanel* m_reference;
    QWidget* m_chartView = nullptr;  ///< QChartView (Qt Charts only in the .cpp)
    QLabel* m_legend;
    QLabel* m_planLine;
    QLabel* m_measureLine;
    QPushButton* m_measureButton;
    std::vector<Point> m_predicted, m_measured;
    std::vector<size_t> m_optionIndices;  ///< m_predicted's candidates in the live models
    double m_budgetMs = 0.0;
    double m_directMs = 0.0;  ///< the Direct frame the plan scaled its costs with
    QString m_measuredReason;
    QString m_planKey;  ///< what the shown plan was made from (no redraw when unchanged)
    /// The view the running measurement renders (a move cancels it).
    Point3f m_measureEye{0.f}, m_measureTarget{0.f};
    /// What the shown plan was made for; m_planDirty: something changed since.
    Point3f m_plannedEye{0.f}, m_plannedTarget{0.f};
    std::string m_plannedMethod;
    bool m_planDirty = true;
    QThread* m_thread = nullptr;
    std::shared_ptr<std::atomic<bool>> m_cancel;
};

}  // namespace lucent::app
