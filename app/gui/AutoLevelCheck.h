// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Auto's level check (lucent/planner/LevelCheck.h) in the app: the viewport's Auto
/// pick is rendered against its method's cheaper levels on a worker thread, off the viewport's
/// frames, and the decision goes to the PreviewRenderer, which then renders the cheapest level
/// that shows the same picture (the status bar's reason says so).
///
/// When: after a frame whose pick (PreviewRenderer::autoPlannedChoice) has a cheaper level and
/// no decision; and again once the artist has stopped editing (paint, lights, η) for
/// RECHECK_IDLE_MS, since paint can make a level needed that was not. A decision holds while
/// the artist paints, so the preview does not switch levels mid-stroke.

#include <QObject>
#include <QString>
#include <QTimer>

#include <lucent/planner/Planner.h>

#include <atomic>
#include <memory>

class QThread;

namespace lucent::app {

class Document;
class Viewport;

class AutoLevelChecker : public QObject {
    Q_OBJECT
public:
    /// Quiet time after the last edit before the pick is checked again, ms.
    static constexpr qint64 RECHECK_IDLE_MS = 1000;

    AutoLevelChecker(Viewport* viewport, Document* doc);
    /// Stops the worker (between two renders) and waits for it.
    ~AutoLevelChecker() override;

    /// After each viewport frame (UI thread): starts a check when one is due (never while Auto
    /// plans with errors measured against a reference: those say more than the check).
    void afterFrame();
    /// The check's tolerance (default planner::LevelTolerance::visibleOnly(): the artist judges
    /// the preview by eye); for the checks started after.
    void setTolerance(const planner::LevelTolerance& tolerance) { m_tolerance = tolerance; }
    [[nodiscard]] const planner::LevelTolerance& tolerance() const { return m_tolerance; }
    /// Off (Edit ▸ Preferences ▸ Auto: Check Quality Levels): no check starts, a running one
    /// is dropped, and the preview renders the models' picks at their own levels again.
    void setEnabled(bool enabled);
    [[nodiscard]] bool isEnabled() const { return m_enabled; }
    [[nodiscard]] bool running() const { return m_thread != nullptr; }
    /// Checks finished (decided or failed) since start.
    [[nodiscard]] int checksDone() const { return m_done; }
    /// The last check's note or failure ("" before one).
    [[nodiscard]] const QString& lastNote() const { return m_lastNote; }

Q_SIGNALS:
    /// A check finished: its note (planner::LevelCheck::note), or why it failed.
    void checked(const QString& note);

private:
    /// Starts a check when the pick has no decision, or when `quiet` (no edit for
    /// RECHECK_IDLE_MS) and the scene was edited since the last check.
    void startIfDue(bool quiet);
    void start();
    void cancel();

    Viewport* m_viewport;
    Document* m_doc;
    QThread* m_thread = nullptr;
    std::shared_ptr<std::atomic<bool>> m_cancel;
    bool m_editedSinceCheck = false;  ///< paint, lights or η changed since the last check began
    /// Runs for RECHECK_IDLE_MS after each edit, then starts a due check (no frame may come
    /// then); while it runs, the scene is not quiet.
    QTimer m_quiet;
    planner::LevelTolerance m_tolerance = planner::LevelTolerance::visibleOnly();
    bool m_enabled = true;
    int m_done = 0;
    QString m_lastNote;
};

}  // namespace lucent::app
