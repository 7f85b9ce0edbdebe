// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The "Reference" dock: the engine's progressive Monte Carlo path tracer
/// (lucent/reference/PathTracer.h) on a worker thread, rendering the current view of a frozen
/// copy of the scene, with the running mean shown after every pass; and the preview's
/// accuracy against it: the preview at the reference's size, a heat-map of the signed 4×4-block
/// relative error (lucent/bench/ErrorMap.h) with its legend, and the block relative L1 and
/// mean ratio beside the reference's noise floor (lucent/bench/ErrorMetrics.h), updated as the
/// reference refines and as the preview converges.

#include <lucent/core/Image.h>
#include <lucent/core/Timer.h>

#include <QImage>
#include <QWidget>

#include <atomic>
#include <memory>

class QComboBox;
class QLabel;
class QProgressBar;
class QPushButton;
class QSpinBox;
class QTabWidget;
class QThread;

namespace lucent {
struct Scene;
}

namespace lucent::app {

class Document;
class ImageView;
class PlanChart;
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

    /// What the picture shows.
    enum class View { Reference = 0, Preview = 1, ErrorMap = 2 };
    void setView(View view);
    /// Compares the viewport's current preview with the reference (at the reference's size and
    /// over its object pixels); the accuracy line says the result, or why there is none (no
    /// reference yet, the view changed since it started). @return whether it compared.
    bool compareWithPreview();
    /// Whether the viewport still shows the view the reference was started from.
    [[nodiscard]] bool viewIsReferenceView() const;
    /// The last comparison's luminance block relative L1 and mean ratio (0 before one).
    [[nodiscard]] double blockRelL1() const { return m_blockRelL1; }
    [[nodiscard]] double meanRatio() const { return m_meanRatio; }

    /// A frozen copy of the document's scene at the viewport's current view, `width` px wide
    /// (the Image setting) with the viewport's aspect: what a reference render starts from
    /// (its own copy of the material, so painting may go on while a worker renders it).
    [[nodiscard]] Scene frozenScene() const;
    /// The same scene sharing the document's material: for use on the UI thread only (the
    /// chart's plan), without copying the volume.
    [[nodiscard]] Scene sceneAtView() const;
    /// Whether a finished (not running, not cleared) reference of the viewport's current view
    /// exists: then referenceMean/Variance/Coverage are its images.
    [[nodiscard]] bool hasFinishedReferenceOfView() const;
    [[nodiscard]] const ImageRgb& referenceMean() const { return m_refMean; }
    [[nodiscard]] const ImageRgb& referenceVariance() const { return m_refVariance; }
    [[nodiscard]] const ImageRgb& referenceCoverage() const { return m_refCoverage; }
    /// The "Run time vs error" page (the Auto plan's chart and the measure button).
    [[nodiscard]] PlanChart* planChart() const { return m_planChart; }
    /// Shows the reference page (0) or the chart page (1).
    void showPage(int page);

Q_SIGNALS:
    void finished();

private:
    void showImage(const QImage& img);
    /// The picture for the chosen view.
    void refreshPicture();
    Document* m_doc;
    Viewport* m_viewport;
    QSpinBox* m_width;
    QSpinBox* m_spp;
    QPushButton* m_startStop;
    QProgressBar* m_progress;
    QLabel* m_info;
    QComboBox* m_view;
    QLabel* m_accuracy;
    QLabel* m_legend;
    ImageView* m_picture;
    QTabWidget* m_pages;
    PlanChart* m_planChart;
    QImage m_image;         ///< the reference, display
    QImage m_previewImage;  ///< the preview at the reference's size, display
    QImage m_errorImage;    ///< the block error heat-map
    ImageRgb m_refMean, m_refVariance, m_refCoverage;  ///< linear; variance and coverage at the end
    /// The view the reference was started from: eye, target (mm), vertical field of view (°).
    Point3f m_refEye{0.f}, m_refTarget{0.f};
    float m_refFovYDeg = 0.f;
    float m_exposure = 1.f;
    double m_blockRelL1 = 0.0, m_meanRatio = 0.0;
    Timer m_sinceCompare;
    QThread* m_thread = nullptr;
    std::shared_ptr<std::atomic<bool>> m_cancel;
};

}  // namespace lucent::app
