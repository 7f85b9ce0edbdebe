// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Auto measuring the scene on its own (lucent/planner/MeasureScene.h,
/// measureWithOwnReference): once the artist pauses, a worker thread renders the exact
/// reference of the viewport's frame at 64 pixels across and each live candidate that fits the
/// frame budget against it, and the PreviewRenderer plans with the measured errors (and its
/// live costs) instead of the models' predictions, which are good to a factor of 1.5–2 only.
/// The measured errors hold through paint and orbits (PreviewRenderer::MeasuredHold::ThisScene),
/// so the preview does not switch back to the models' pick while the artist paints; the next
/// pause measures again.
///
/// When: QUIET_MS of quiet after the scene was loaded or edited (paint, lights, η), while Auto is
/// the preview method, not while the level check's worker runs (one background render at a
/// time) nor while refinement is paused (the live-cost calibration stops a running one). Edit ▸
/// Preferences ▸ Auto: Measure the Scene turns it on or off (on by default where the app keeps
/// settings; off for scripted runs and tests).

#include <QObject>
#include <QString>
#include <QTimer>

#include <atomic>
#include <memory>

class QThread;

namespace lucent::app {

class Document;
class Viewport;

class AutoMeasurer : public QObject {
    Q_OBJECT
public:
    /// Quiet time after the last edit (or the scene's load) before the scene is measured, ms.
    static constexpr int QUIET_MS = 3000;
    /// The frame measured: pixels across (the reference's cost grows with them) and the
    /// reference's samples per pixel (its noise floor 0.02–0.05 on the shipped scenes).
    static constexpr int WIDTH = 64;
    static constexpr int REFERENCE_SPP = 128;

    AutoMeasurer(Viewport* viewport, Document* doc);
    /// Stops the worker (between two renders) and waits for it.
    ~AutoMeasurer() override;

    /// After each viewport frame (UI thread): starts a measurement when one is due.
    void afterFrame();
    /// Off: no measurement starts, a running one is dropped, and Auto plans with its models
    /// again (a measurement of the Reference dock's view is left alone).
    void setEnabled(bool enabled);
    [[nodiscard]] bool isEnabled() const { return m_enabled; }
    /// Stops a running measurement (between two renders) without applying it; the scene is
    /// measured again when due (Viewport::setRefinementPaused: the live-cost calibration).
    void stopForNow();
    /// The quiet time before a measurement, ms (QUIET_MS; tests shorten it).
    void setQuietMs(int ms);
    [[nodiscard]] bool running() const { return m_thread != nullptr; }
    /// Measurements finished (applied or failed) since start.
    [[nodiscard]] int measurementsDone() const { return m_done; }
    /// The last measurement's summary or failure ("" before one).
    [[nodiscard]] const QString& lastNote() const { return m_lastNote; }
    /// The last applied measurement's reference noise floor (the plan's tie margin), or 0.
    [[nodiscard]] double lastReferenceNoise() const { return m_lastNoise; }

Q_SIGNALS:
    /// A measurement finished: its summary, or why it failed.
    void measured(const QString& note);

private:
    void startIfDue();
    void start();
    void cancel();

    Viewport* m_viewport;
    Document* m_doc;
    QThread* m_thread = nullptr;
    std::shared_ptr<std::atomic<bool>> m_cancel;
    /// The scene was loaded or edited since the last measurement began (or never measured).
    bool m_due = true;
    /// This measurer's errors are in the renderer (so a drop there, e.g. new live costs, makes
    /// a measurement due again).
    bool m_applied = false;
    QTimer m_quiet;  ///< runs for the quiet time after each edit; while it runs, no start
    bool m_enabled = true;
    int m_done = 0;
    QString m_lastNote;
    double m_lastNoise = 0.0;
};

}  // namespace lucent::app
