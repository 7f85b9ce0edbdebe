// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The "Reference" dock: the engine's progressive Monte Carlo path tracer
/// (lucent/reference/PathTracer.h) on a worker thread, rendering the current view of a frozen
/// copy of the scene, with the running mean shown after every pass.

#include <QImage>
#include <QWidget>

#include <atomic>
#include <memory>

class QLabel;
class QProgressBar;
class QPushButton;
class QSpinBox;
class QThread;

namespace lucent::app {

class Document;
class ImageView;
class Viewport;

class ReferencePanel : public QWidget {
    Q_OBJECT
public:
    ReferencePanel(Document* doc, Viewport* viewport, QWidget* parent = nullptr);
    ~ReferencePanel() override;

    /// Image width in pixels and samples per pixel of the next render.
    void setParameters(int width, int spp);
    /// Starts a render of the current view (`width` × height from the viewport's aspect).
    void start();
    /// Asks the running render to stop after its current tile; returns at once.
    void stop();
    [[nodiscard]] bool isRunning() const { return m_thread != nullptr; }
    /// Latest progressive image (display sRGB after the viewport's exposure).
    [[nodiscard]] const QImage& image() const { return m_image; }

Q_SIGNALS:
    void finished();

private:
    void showImage(const QImage& img);
    Document* m_doc;
    Viewport* m_viewport;
    QSpinBox* m_width;
    QSpinBox* m_spp;
    QPushButton* m_startStop;
    QProgressBar* m_progress;
    QLabel* m_info;
    ImageView* m_picture;
    QImage m_image;
    QThread* m_thread = nullptr;
    std::shared_ptr<std::atomic<bool>> m_cancel;
};

}  // namespace lucent::app
