// SPDX-License-Identifier: MIT
#include "AutoLevelCheck.h"

#include "Document.h"
#include "PreviewRenderer.h"
#include "Viewport.h"

#include <lucent/planner/LevelCheck.h>

#include <QThread>

#include <algorithm>

namespace lucent::app {

AutoLevelChecker::AutoLevelChecker(Viewport* viewport, Document* doc)
    : QObject(viewport), m_viewport(viewport), m_doc(doc) {
    m_quiet.setSingleShot(true);
    m_quiet.setInterval(int(RECHECK_IDLE_MS));
    m_quiet.setTimerType(Qt::PreciseTimer);  // a coarse timer may fire up to 5 % early
    connect(&m_quiet, &QTimer::timeout, this, [this] { startIfDue(/*quiet=*/true); });
    const auto edited = [this] {
        m_editedSinceCheck = true;
        m_quiet.start();
    };
    connect(m_doc, &Document::materialEdited, this, edited);
    connect(m_doc, &Document::sceneEdited, this, edited);
    // Another scene: a check of the old one must not reach the renderer (which dropped its
    // decisions).
    connect(m_doc, &Document::sceneReplaced, this, [this] {
        cancel();
        m_editedSinceCheck = false;
    });
}

AutoLevelChecker::~AutoLevelChecker() {
    cancel();
    if (m_thread) {
        m_thread->wait();
        delete m_thread;
    }
}

void AutoLevelChecker::cancel() {
    if (m_cancel)
        m_cancel->store(true);
}

void AutoLevelChecker::setEnabled(bool enabled) {
    if (enabled == m_enabled)
        return;
    m_enabled = enabled;
    if (!enabled) {
        cancel();
        m_viewport->previewRenderer().clearAutoLevelDecisions();
    }
    m_viewport->update();  // off: the picks' own levels; on: the next frame starts a check
}

void AutoLevelChecker::afterFrame() {
    startIfDue(/*quiet=*/!m_quiet.isActive());  // running: an edit less than RECHECK_IDLE_MS ago
}

void AutoLevelChecker::startIfDue(bool quiet) {
    // One background render at a time (Auto's measurement starts this check when done).
    if (!m_enabled || m_thread || !m_doc->hasObject() || m_viewport->refinementPaused() ||
        m_viewport->autoMeasurer().running())
        return;
    const PreviewRenderer& preview = m_viewport->previewRenderer();
    const planner::AutoChoice* planned = preview.autoPlannedChoice();
    if (!planned || preview.usesMeasuredModels() || m_tolerance.off())
        return;
    const std::vector<std::string> levels =
        planner::modelLevels(PreviewRenderer::liveModels(), planned->candidate());
    const auto at = std::find(levels.begin(), levels.end(), planned->setting);
    if (at == levels.end() || at == levels.begin())
        return;  // nothing cheaper to check
    const bool undecided = !preview.hasAutoLevelDecisionFor(*planned);
    const bool quietAfterEdit = m_editedSinceCheck && quiet;
    if (undecided || quietAfterEdit)
        start();
}

void AutoLevelChecker::start() {
    const planner::AutoChoice choice = *m_viewport->previewRenderer().autoPlannedChoice();
    // A frozen copy of what the viewport shows: painting may go on while the worker renders.
    const Scene scene = m_viewport->frozenSceneOfView(std::max(m_viewport->width(), 16));
    m_editedSinceCheck = false;
    m_cancel = std::make_shared<std::atomic<bool>>(false);
    auto cancel = m_cancel;
    auto check = std::make_shared<planner::LevelCheck>();
    auto error = std::make_shared<QString>();
    const planner::LevelTolerance tolerance = m_tolerance;
    m_thread = QThread::create([scene, choice, cancel, check, error, tolerance] {
        planner::LevelCheckOptions options;
        options.tolerance = tolerance;
        options.render.backend = methods::Backend::Gl;  // the preview's backend
        options.cancel = cancel.get();
        try {
            *check = planner::checkLevels(scene, PreviewRenderer::liveModels(), choice, options);
        } catch (const std::exception& ex) {
            *error = QString::fromUtf8(ex.what());
        }
    });
    connect(m_thread, &QThread::finished, this, [this, choice, cancel, check, error] {
        m_thread->deleteLater();
        m_thread = nullptr;
        ++m_done;
        if (cancel->load())
            return;  // another scene, or closing
        if (!error->isEmpty()) {
            // Keep the pick: the check is an optimisation, its failure is not the preview's.
            m_lastNote = tr("level check failed: %1").arg(*error);
        } else {
            PreviewRenderer::AutoLevelDecision d;
            d.method = choice.candidate();
            d.planned = choice.setting;
            d.kept = check->setting;
            d.note = check->note;
            d.sceneClass = choice.plan.sceneClass;
            m_viewport->previewRenderer().setAutoLevelDecision(d);
            m_lastNote = QString::fromStdString(check->note);
            m_viewport->update();
        }
        Q_EMIT checked(m_lastNote);
    });
    m_thread->start(QThread::LowPriority);
}

}  // namespace lucent::app
