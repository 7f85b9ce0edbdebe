// SPDX-License-Identifier: MIT
#include "AutoMeasure.h"

#include "Document.h"
#include "PreviewRenderer.h"
#include "Viewport.h"

#include <lucent/planner/MeasureScene.h>

#include <QThread>

#include <algorithm>

namespace lucent::app {

AutoMeasurer::AutoMeasurer(Viewport* viewport, Document* doc)
    : QObject(viewport), m_viewport(viewport), m_doc(doc) {
    m_quiet.setSingleShot(true);
    m_quiet.setInterval(QUIET_MS);
    m_quiet.setTimerType(Qt::PreciseTimer);
    // No frame may come once the viewport is idle: the timer's end starts a due measurement.
    connect(&m_quiet, &QTimer::timeout, this, [this] { startIfDue(); });
    const auto edited = [this] {
        m_due = true;
        m_quiet.start();
    };
    connect(m_doc, &Document::materialEdited, this, edited);
    connect(m_doc, &Document::sceneEdited, this, edited);
    // Another scene: a measurement of the old one must not reach the renderer.
    connect(m_doc, &Document::sceneReplaced, this, [this, edited] {
        cancel();
        m_applied = false;
        edited();
    });
    m_quiet.start();  // the first scene is measured once it has been shown quietly
}

AutoMeasurer::~AutoMeasurer() {
    cancel();
    if (m_thread) {
        m_thread->wait();
        delete m_thread;
    }
}

void AutoMeasurer::cancel() {
    if (m_cancel)
        m_cancel->store(true);
}

void AutoMeasurer::stopForNow() {
    if (!m_thread)
        return;
    cancel();
    m_due = true;
}

void AutoMeasurer::setQuietMs(int ms) {
    m_quiet.setInterval(std::max(ms, 0));
    if (m_quiet.isActive())
        m_quiet.start();
}

void AutoMeasurer::setEnabled(bool enabled) {
    if (enabled == m_enabled)
        return;
    m_enabled = enabled;
    if (!enabled) {
        cancel();
        PreviewRenderer& preview = m_viewport->previewRenderer();
        if (m_applied && preview.measuredHold() == PreviewRenderer::MeasuredHold::ThisScene)
            preview.setMeasuredModels(nullptr);
        m_applied = false;
    } else {
        m_due = true;
        m_quiet.start();
    }
    m_viewport->update();
}

void AutoMeasurer::afterFrame() {
    const PreviewRenderer& preview = m_viewport->previewRenderer();
    if (m_applied && !preview.hasMeasuredModels()) {
        // The renderer dropped them (other lights, η, live costs): measure again.
        m_applied = false;
        m_due = true;
    }
    startIfDue();
}

void AutoMeasurer::startIfDue() {
    // One background render at a time: the level check's worker renders with GL too, and two
    // of them beside the preview oversubscribe a 2-core machine (it starts this one when done).
    if (!m_enabled || m_thread || !m_due || m_quiet.isActive() || !m_doc->hasObject() ||
        m_viewport->refinementPaused() || m_viewport->levelChecker().running())
        return;
    const PreviewRenderer& preview = m_viewport->previewRenderer();
    if (!preview.autoPlannedChoice())
        return;  // Auto is not the preview method, or its plan waits for the Direct frame
    if (preview.hasMeasuredModels() &&
        preview.measuredHold() == PreviewRenderer::MeasuredHold::ThisView)
        return;  // the Reference dock's measurement of this view: it says more
    start();
}

void AutoMeasurer::start() {
    const planner::AutoChoice& planned = *m_viewport->previewRenderer().autoPlannedChoice();
    // The live candidates Auto could pick: those within the frame budget (every usable one
    // when none fits, as the planner then takes the least late).
    std::vector<size_t> which;
    for (const planner::Option& o : planned.plan.options)
        if (o.fits)
            which.push_back(o.index);
    if (which.empty())
        for (const planner::Option& o : planned.plan.options)
            which.push_back(o.index);
    // A frozen copy of what the viewport shows: painting may go on while the worker renders.
    const Scene scene = m_viewport->frozenSceneOfView(std::max(m_viewport->width(), 16));
    m_due = false;
    m_cancel = std::make_shared<std::atomic<bool>>(false);
    auto cancel = m_cancel;
    auto result = std::make_shared<planner::OwnReferenceMeasurement>();
    auto error = std::make_shared<QString>();
    m_thread = QThread::create([scene, which, cancel, result, error] {
        planner::OwnReferenceOptions o;
        o.width = WIDTH;
        o.referenceSpp = REFERENCE_SPP;
        o.referenceThreads = 1;  // the other core keeps the live preview going
        o.which = which;
        o.render.backend = methods::Backend::Gl;  // the preview's backend
        o.cancel = cancel.get();
        try {
            *result = planner::measureWithOwnReference(scene, PreviewRenderer::liveModels(), o);
        } catch (const std::exception& ex) {
            *error = QString::fromUtf8(ex.what());
        }
    });
    connect(m_thread, &QThread::finished, this, [this, cancel, result, error] {
        m_thread->deleteLater();
        m_thread = nullptr;
        ++m_done;
        if (cancel->load() || result->measurement.cancelled)
            return;  // another scene, switched off, or closing
        if (!error->isEmpty()) {
            // Auto keeps planning with its models: the measurement refines, it is not needed.
            m_lastNote = tr("measuring the scene failed: %1").arg(*error);
        } else {
            int measured = 0;
            for (const planner::CandidateMeasurement& c : result->measurement.candidates)
                measured += c.ok() ? 1 : 0;
            m_viewport->previewRenderer().setMeasuredModels(
                std::make_shared<const planner::Models>(
                    planner::measuredModels(PreviewRenderer::liveModels(), result->measurement,
                                            planner::MeasuredParts::ErrorsOnly)),
                result->referenceNoise, PreviewRenderer::MeasuredHold::ThisScene);
            m_applied = true;
            m_lastNoise = result->referenceNoise;
            m_lastNote = tr("measured %1 candidates against the exact reference (%2×%3, %4 spp, "
                            "noise floor %5) in %6 s")
                             .arg(measured)
                             .arg(result->width)
                             .arg(result->height)
                             .arg(result->referenceSpp)
                             .arg(result->referenceNoise, 0, 'f', 3)
                             .arg(result->referenceSeconds, 0, 'f', 1);
            m_viewport->update();
        }
        Q_EMIT measured(m_lastNote);
    });
    m_thread->start(QThread::LowPriority);
}

}  // namespace lucent::app
