// SPDX-License-Identifier: MIT
/// @file
/// @brief The Reference dock's run-time-vs-error chart (PlanChart.h).

#include "PlanChart.h"

#include "Document.h"
#include "PreviewRenderer.h"
#include "ReferencePanel.h"
#include "Viewport.h"

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>
#include <lucent/core/Timer.h>
#include <lucent/planner/AutoMethod.h>
#include <lucent/planner/LiveCosts.h>
#include <lucent/planner/MeasureScene.h>

#include <QChart>
#include <QChartView>
#include <QCoreApplication>
#include <QEvent>
#include <QLabel>
#include <QLineSeries>
#include <QLogValueAxis>
#include <QPointer>
#include <QPushButton>
#include <QScatterSeries>
#include <QThread>
#include <QVBoxLayout>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

namespace lucent::app {

namespace {

/// The plan of the current view: the viewport's own when it runs Auto, else the one Auto would
/// make for the view (the preview's live candidates and frame budget).
struct ShownPlan {
    planner::AutoChoice choice;
    double directMs = 0.0;  ///< the Direct frame the costs are scaled with
    bool fromViewport = false;
};

/// The Direct frame to scale costs with: Auto's timed one, else the live cost table's (the
/// machine the live costs were measured on), else the planner's default.
double directFrameMs(Viewport& viewport) {
    const double timed = viewport.previewRenderer().autoDirectMs();
    if (timed > 0)
        return timed;
    const double measured = PreviewRenderer::liveCostTable().inUse.costs.directMs;
    return measured > 0 ? measured : planner::Budget().directMs;
}

QString candidateLabel(const planner::CandidateModel& c) {
    return QString::fromStdString(c.method + " " + c.setting);
}

/// Registry name of a candidate ("sslpv:paper" → "sslpv").
std::string registryName(const std::string& method) {
    return method.substr(0, method.find(':'));
}

constexpr const char* SERIES_PREDICTED = "predictedSeries";
constexpr const char* SERIES_CHOSEN = "chosenSeries";
constexpr const char* SERIES_CURRENT = "currentMethodSeries";
constexpr const char* SERIES_MEASURED = "measuredSeries";
constexpr const char* SERIES_MEASURED_CHOSEN = "measuredChosenSeries";
constexpr const char* SERIES_BUDGET = "budgetSeries";

QScatterSeries* scatter(const QString& name, const char* objectName, QColor colour,
                        QScatterSeries::MarkerShape shape, double size) {
    auto* s = new QScatterSeries;
    s->setName(name);
    s->setObjectName(QString::fromLatin1(objectName));
    s->setColor(colour);
    s->setBorderColor(colour.darker(160));
    s->setMarkerShape(shape);
    s->setMarkerSize(size);
    return s;
}

/// One legend entry: the series' marker in its colour, then its name.
QString legendEntry(const QAbstractSeries* s) {
    QString glyph = QStringLiteral("┆");  // the budget line
    QColor colour(120, 120, 120);
    if (const auto* sc = qobject_cast<const QScatterSeries*>(s)) {
        colour = sc->color();
        switch (sc->markerShape()) {
            case QScatterSeries::MarkerShapeStar:
                glyph = QStringLiteral("★");
                break;
            case QScatterSeries::MarkerShapeRectangle:
                glyph = QStringLiteral("■");
                break;
            case QScatterSeries::MarkerShapeTriangle:
                glyph = QStringLiteral("▲");
                break;
            case QScatterSeries::MarkerShapePentagon:
                glyph = QStringLiteral("⬟");
                break;
            default:
                glyph = QStringLiteral("●");
        }
    }
    return QStringLiteral("<span style='color:%1'>%2</span>&nbsp;%3")
        .arg(colour.name(), glyph, s->name().toHtmlEscaped());
}

}  // namespace

PlanChart::PlanChart(Document* doc, Viewport* viewport, ReferencePanel* reference, QWidget* parent)
    : QWidget(parent), m_doc(doc), m_viewport(viewport), m_reference(reference) {
    auto* layout = new QVBoxLayout(this);
    auto* view = new QChartView;
    view->setObjectName(QStringLiteral("planChartView"));
    view->setRenderHint(QPainter::Antialiasing);
    view->setToolTip(
        tr("Each candidate of the Auto planner: its frame time (ms) against its block error, "
           "the 4×4-block relative L1 of luminance against the exact reference (the number the "
           "Reference page reports). Both axes are logarithmic."));
    view->setMinimumSize(200, 240);
    // The legend is a label under the chart: Qt Charts' legend is one row, and the dock (about
    // 390 px on a 1366×768 screen) cuts its names.
    view->chart()->legend()->setVisible(false);
    view->chart()->setMargins(QMargins(2, 2, 2, 2));
    m_chartView = view;
    layout->addWidget(view, 1);
    m_legend = new QLabel;
    m_legend->setObjectName(QStringLiteral("planChartLegend"));
    m_legend->setWordWrap(true);
    layout->addWidget(m_legend);
    m_planLine = new QLabel;
    m_planLine->setObjectName(QStringLiteral("planChartPlan"));
    m_planLine->setWordWrap(true);
    m_planLine->setTextInteractionFlags(Qt::TextSelectableByMouse);
    layout->addWidget(m_planLine);
    m_measureButton = new QPushButton(tr("Measure this scene"));
    m_measureButton->setObjectName(QStringLiteral("planChartMeasure"));
    m_measureButton->setToolTip(
        tr("Renders every candidate on this view (at the reference's size), times it against "
           "a Direct render and, with a finished reference of this view, measures its block "
           "error; then plans with the measured numbers."));
    layout->addWidget(m_measureButton);
    m_measureLine = new QLabel(tr("Points are the planner's predictions."));
    m_measureLine->setObjectName(QStringLiteral("planChartMeasured"));
    m_measureLine->setWordWrap(true);
    m_measureLine->setTextInteractionFlags(Qt::TextSelectableByMouse);
    layout->addWidget(m_measureLine);

    connect(m_measureButton, &QPushButton::clicked, this, [this] {
        if (isMeasuring())
            cancelMeasurement();
        else
            measure();
    });
    m_reference->installEventFilter(this);
    connect(m_viewport, &Viewport::autoPlanChanged, this, [this] { refreshPlan(); });
    // A measurement is of one scene and view: any edit makes it stale, so it stops and its
    // points go; the plan is made again.
    for (auto signal :
         {&Document::sceneReplaced, &Document::materialEdited, &Document::sceneEdited})
        connect(m_doc, signal, this, [this] {
            cancelMeasurement();
            m_planDirty = true;
            if (!m_measured.empty()) {
                m_measured.clear();
                m_measuredReason.clear();
                redraw();
            }
        });
    // With a fixed method the viewport makes no plan: plan for the view when something it
    // depends on changed, at most once a second and only while the page is shown (planning
    // measures the painted volume). Queued: the viewport emits from inside its paintGL.
    auto since = std::make_shared<Timer>();
    connect(
        m_viewport, &Viewport::frameRendered, this,
        [this, since] {
            const OrbitCamera& cam = m_viewport->camera();
            if (isMeasuring() && (cam.eye() != m_measureEye || cam.target != m_measureTarget))
                cancelMeasurement();  // the view moved
            if (cam.eye() != m_plannedEye || cam.target != m_plannedTarget ||
                m_viewport->renderSettings().method != m_plannedMethod)
                m_planDirty = true;
            if (m_planDirty && isVisible() && since->elapsedMs() > 1000.0) {
                since->reset();
                refreshPlan();
            }
        },
        Qt::QueuedConnection);
}

void PlanChart::showEvent(QShowEvent* event) {
    QWidget::showEvent(event);
    if (m_planDirty)
        refreshPlan();
}

PlanChart::~PlanChart() {
    if (m_thread) {
        m_cancel->store(true);
        m_thread->wait();
        delete m_thread;
    }
}

bool PlanChart::eventFilter(QObject* watched, QEvent* event) {
    // The dock was closed or put behind another (the whole panel hides), not merely the other
    // page shown: a measurement may go on while the reference renders.
    if (watched == m_reference && event->type() == QEvent::Hide)
        cancelMeasurement();
    return QWidget::eventFilter(watched, event);
}

QString PlanChart::chosenLabel() const {
    for (const Point& p : m_predicted)
        if (p.chosen)
            return p.label;
    return {};
}

void PlanChart::refreshPlan() {
    m_planDirty = false;
    m_plannedEye = m_viewport->camera().eye();
    m_plannedTarget = m_viewport->camera().target;
    m_plannedMethod = m_viewport->renderSettings().method;
    const auto noPlan = [this](const QString& why) {
        m_predicted.clear();
        m_optionIndices.clear();
        m_planKey.clear();
        m_planLine->setText(why);
        redraw();
    };
    if (!m_doc->hasObject()) {
        noPlan(tr("No object: nothing to plan."));
        return;
    }
    const planner::Models& models = PreviewRenderer::liveModels();
    const bool isAuto = m_viewport->renderSettings().method == AUTO_METHOD;
    ShownPlan shown;
    shown.directMs = directFrameMs(*m_viewport);
    try {
        const planner::AutoChoice* live = m_viewport->previewRenderer().autoChoice();
        if (isAuto && live) {
            shown.choice = *live;
            shown.directMs = live->directMs;
            shown.fromViewport = true;
        } else {
            planner::Budget budget;
            budget.directMs = shown.directMs;
            shown.choice =
                planner::chooseMethod(m_reference->sceneAtView(), models, budget,
                                      /*glAvailable=*/true, nullptr, methods::Backend::Gl);
        }
    } catch (const Error& e) {
        noPlan(tr("No plan: %1").arg(QString::fromUtf8(e.what())));
        return;
    }
    const std::string current = m_viewport->renderSettings().method;
    std::vector<Point> points;
    std::vector<size_t> indices;
    QString key;
    for (const planner::Option& o : shown.choice.plan.options) {
        const planner::CandidateModel& c = models.candidates[o.index];
        Point p;
        p.label = candidateLabel(c);
        p.ms = o.ms;
        p.error = o.error;
        p.chosen = o.index == shown.choice.plan.choice;
        p.currentMethod = !isAuto && registryName(c.method) == current;
        key += QStringLiteral("%1|%2|%3|%4|%5;")
                   .arg(p.label)
                   .arg(p.ms)
                   .arg(p.error)
                   .arg(p.chosen)
                   .arg(p.currentMethod);
        points.push_back(p);
        indices.push_back(o.index);
    }
    const QString reason = QString::fromStdString(shown.choice.plan.reason);
    if (shown.fromViewport)
        m_planLine->setText(tr("Auto (predicted): %1").arg(reason));
    else if (isAuto)  // the preview still times the Direct frame it plans with
        m_planLine->setText(
            tr("Auto (predicted, before the preview's first plan): %1").arg(reason));
    else
        m_planLine->setText(tr("The preview runs %1; Auto would choose (predicted): %2")
                                .arg(QString::fromStdString(current), reason));
    m_directMs = shown.directMs;
    if (key == m_planKey)
        return;
    m_planKey = key;
    m_predicted = std::move(points);
    m_optionIndices = std::move(indices);
    m_budgetMs = planner::Budget().frameMs;  // the preview plans with the default budget
    redraw();
}

void PlanChart::cancelMeasurement() {
    if (m_cancel)
        m_cancel->store(true);
}

void PlanChart::measure() {
    if (m_thread || !m_doc->hasObject() || m_optionIndices.empty())
        return;
    Scene scene = m_reference->frozenScene();
    // With a finished reference of this view: its size and its pixels, the dock's metric.
    auto ref = std::make_shared<ImageRgb>();
    auto variance = std::make_shared<ImageRgb>();
    auto mask = std::make_shared<std::vector<uint8_t>>();
    const bool withReference = m_reference->hasFinishedReferenceOfView();
    if (withReference) {
        *ref = m_reference->referenceMean();
        *variance = m_reference->referenceVariance();
        *mask = bench::maskFromImage(m_reference->referenceCoverage());
        scene.camera.width = ref->width();
        scene.camera.height = ref->height();
    }
    m_measureEye = scene.camera.position;
    m_measureTarget = scene.camera.target;
    const std::vector<size_t> which = m_optionIndices;
    const double directMs = m_directMs;
    m_measured.clear();
    m_measuredReason.clear();
    m_cancel = std::make_shared<std::atomic<bool>>(false);
    auto cancel = m_cancel;
    auto result = std::make_shared<planner::SceneMeasurement>();
    auto error = std::make_shared<QString>();
    auto measuredChoice = std::make_shared<planner::AutoChoice>();
    QPointer<PlanChart> self(this);
    m_thread = QThread::create([scene, ref, variance, mask, withReference, which, directMs, cancel,
                                result, error, measuredChoice, self] {
        planner::MeasureOptions opt;
        if (withReference) {
            opt.reference = ref.get();
            opt.referenceVariance = variance->isEmpty() ? nullptr : variance.get();
            opt.mask = mask.get();
        }
        opt.which = which;
        opt.render.backend = methods::Backend::Gl;  // the preview's backend
        opt.cancel = cancel.get();
        opt.progress = [self](size_t done, size_t total, const planner::CandidateMeasurement* m) {
            const QString last =
                m ? QString::fromStdString(m->method + " " + m->setting) : QStringLiteral("direct");
            QMetaObject::invokeMethod(QCoreApplication::instance(), [self, done, total, last] {
                if (self)
                    self->m_measureLine->setText(tr("Measuring: %1 of %2 rendered (last: %3)…")
                                                     .arg(done)
                                                     .arg(total)
                                                     .arg(last));
            });
        };
        try {
            const planner::Models& models = PreviewRenderer::liveModels();
            *result = planner::measureCandidates(scene, models, opt);
            if (!result->cancelled) {
                planner::Budget budget;
                budget.directMs = directMs;
                *measuredChoice =
                    planner::chooseMethod(scene, planner::measuredModels(models, *result), budget,
                                          /*glAvailable=*/true, nullptr, methods::Backend::Gl);
            }
        } catch (const std::exception& ex) {
            *error = QString::fromUtf8(ex.what());
        }
    });
    connect(m_thread, &QThread::finished, this,
            [this, result, error, measuredChoice, withReference, directMs] {
                m_thread->deleteLater();
                m_thread = nullptr;
                m_measureButton->setText(tr("Measure this scene"));
                if (!error->isEmpty()) {
                    m_measureLine->setText(tr("Measurement failed: %1").arg(*error));
                } else if (result->cancelled) {
                    m_measureLine->setText(
                        tr("Measurement stopped (the scene or view changed, or it was "
                           "cancelled)."));
                } else {
                    showMeasurement(*result, *measuredChoice, withReference, directMs);
                    if (withReference) {
                        // The measured errors update Auto's live plan; the live costs stay
                        // (the measured times are offline renders, another quantity).
                        m_viewport->previewRenderer().setMeasuredModels(
                            std::make_shared<const planner::Models>(
                                planner::measuredModels(PreviewRenderer::liveModels(), *result,
                                                        planner::MeasuredParts::ErrorsOnly)));
                        m_measureLine->setText(
                            m_measureLine->text() +
                            tr(" Auto now plans with these errors (and its live costs) until "
                               "the scene or the view changes."));
                        m_viewport->update();
                    }
                }
                redraw();
                Q_EMIT measurementFinished();
            });
    m_measureButton->setText(tr("Stop measuring"));
    m_measureLine->setText(tr("Measuring…"));
    m_thread->start(QThread::LowPriority);
}

void PlanChart::showMeasurement(const planner::SceneMeasurement& result,
                                const planner::AutoChoice& measuredChoice, bool withReference,
                                double directMs) {
    const planner::Models& models = PreviewRenderer::liveModels();
    const QString chosen = measuredChoice.plan.valid
                               ? candidateLabel(models.candidates[measuredChoice.plan.choice])
                               : QString();
    for (const planner::CandidateMeasurement& m : result.candidates) {
        if (!m.ok())
            continue;
        Point p;
        p.label = QString::fromStdString(m.method + " " + m.setting);
        // In the plan's unit: the measured ratio times the Direct frame the predictions are
        // scaled with.
        p.ms = m.costRatio * directMs;
        p.error = m.blockRelL1;  // < 0: not measured (no reference)
        p.chosen = p.label == chosen;
        m_measured.push_back(p);
    }
    m_measuredReason = QString::fromStdString(measuredChoice.plan.reason);
    m_measureLine->setText(
        (withReference ? tr("Measured on this scene (offline renders: time and error; Direct "
                            "frame %1 ms): %2")
                       : tr("Measured on this scene (offline renders: time only, render a "
                            "reference of this view for the error; Direct frame %1 ms): %2"))
            .arg(result.directMs, 0, 'f', 1)
            .arg(m_measuredReason));
}

void PlanChart::redraw() {
    auto* view = static_cast<QChartView*>(m_chartView);
    QChart* chart = view->chart();
    chart->removeAllSeries();
    for (QAbstractAxis* a : chart->axes()) {
        chart->removeAxis(a);
        delete a;
    }
    auto* predicted = scatter(tr("Predicted"), SERIES_PREDICTED, QColor(90, 140, 220),
                              QScatterSeries::MarkerShapeCircle, 9);
    auto* chosen = scatter(tr("Auto's choice"), SERIES_CHOSEN, QColor(230, 120, 20),
                           QScatterSeries::MarkerShapeStar, 18);
    auto* current = scatter(tr("Current method"), SERIES_CURRENT, QColor(40, 170, 90),
                            QScatterSeries::MarkerShapeRectangle, 13);
    auto* measured = scatter(tr("Measured (offline render)"), SERIES_MEASURED, QColor(200, 40, 60),
                             QScatterSeries::MarkerShapeTriangle, 11);
    auto* measuredChosen = scatter(tr("Choice by the measurements"), SERIES_MEASURED_CHOSEN,
                                   QColor(120, 30, 160), QScatterSeries::MarkerShapePentagon, 17);
    double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
    double xlo = m_budgetMs > 0 ? m_budgetMs : lo, xhi = m_budgetMs;
    const auto add = [&](QScatterSeries* s, const Point& p, double error) {
        const double pct = 100.0 * error;
        s->append(p.ms, pct);
        lo = std::min(lo, pct);
        hi = std::max(hi, pct);
        xlo = std::min(xlo, p.ms);
        xhi = std::max(xhi, p.ms);
    };
    for (const Point& p : m_predicted) {
        add(predicted, p, p.error);
        if (p.chosen)
            add(chosen, p, p.error);
        if (p.currentMethod)
            add(current, p, p.error);
    }
    for (const Point& p : m_measured) {
        // No reference: the measured time at the predicted error of the same candidate.
        double error = p.error;
        if (error < 0)
            for (const Point& q : m_predicted)
                if (q.label == p.label)
                    error = q.error;
        if (!(error > 0) || !(p.ms > 0))
            continue;  // a log axis has no 0
        add(measured, p, error);
        if (p.chosen)
            add(measuredChosen, p, error);
    }
    QList<QAbstractSeries*> series{predicted, chosen};
    const auto keepIfAny = [&series](QScatterSeries* s) {
        if (s->count() > 0)
            series.push_back(s);
        else
            delete s;
    };
    keepIfAny(current);
    keepIfAny(measured);
    keepIfAny(measuredChosen);
    if (!(hi > 0)) {
        lo = 1.0;
        hi = 100.0;
    }
    if (!(xhi > 0)) {
        xlo = 1.0;
        xhi = 100.0;
    }
    const double ylo = lo / 1.5, yhi = hi * 1.5;
    if (m_budgetMs > 0 && std::isfinite(m_budgetMs)) {
        auto* budget = new QLineSeries;
        budget->setName(tr("Frame budget %1 ms").arg(m_budgetMs, 0, 'f', 0));
        budget->setObjectName(QString::fromLatin1(SERIES_BUDGET));
        budget->setPen(QPen(QColor(120, 120, 120), 1.5, Qt::DashLine));
        budget->append(m_budgetMs, ylo);
        budget->append(m_budgetMs, yhi);
        series.push_front(budget);
    }
    const auto logAxis = [](const QString& title, double from, double to) {
        auto* a = new QLogValueAxis;
        a->setTitleText(title);
        a->setLabelFormat(QStringLiteral("%g"));
        a->setBase(10);
        a->setMinorTickCount(-1);
        a->setRange(from, to);
        return a;
    };
    QLogValueAxis* x = logAxis(tr("Frame time (ms)"), xlo / 1.5, xhi * 1.5);
    QLogValueAxis* y = logAxis(tr("Block error (%)"), ylo, yhi);
    chart->addAxis(x, Qt::AlignBottom);
    chart->addAxis(y, Qt::AlignLeft);
    QStringList legend;
    for (QAbstractSeries* s : series) {
        chart->addSeries(s);
        s->attachAxis(x);
        s->attachAxis(y);
        legend << legendEntry(s);
    }
    m_legend->setText(legend.join(QStringLiteral(" &nbsp; ")));
}

}  // namespace lucent::app
