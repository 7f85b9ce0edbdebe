// SPDX-License-Identifier: MIT
/// @file
/// @brief Reference dock: progressive path tracing off the UI thread.

#include "ReferencePanel.h"

#include "Document.h"
#include "ImageView.h"
#include "PlanChart.h"
#include "Viewport.h"

#include <lucent/bench/ErrorMap.h>
#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>
#include <lucent/reference/PathTracer.h>

#include <QComboBox>
#include <QFormLayout>
#include <QPainter>
#include <QCoreApplication>
#include <QLabel>
#include <QPointer>
#include <QProgressBar>
#include <QPushButton>
#include <QSpinBox>
#include <QTabWidget>
#include <QThread>
#include <QVBoxLayout>

namespace lucent::app {

namespace {

/// Linear radiance → display: exposure, Reinhard curve, sRGB (the viewport's mapping, so the
/// two images compare directly).
QImage toDisplay(const ImageRgb& img, float exposure) {
    QImage out(img.width(), img.height(), QImage::Format_RGB32);
    ToneMap tm;
    tm.exposure = exposure;
    tm.curve = ToneMap::Curve::Reinhard;
    for (int y = 0; y < img.height(); ++y) {
        auto* row = reinterpret_cast<QRgb*>(out.scanLine(y));
        for (int x = 0; x < img.width(); ++x) {
            const Rgb d = toneMapToDisplay(img.at(x, y), tm);
            row[x] = qRgb(int(std::clamp(d.r, 0.f, 1.f) * 255.f + 0.5f),
                          int(std::clamp(d.g, 0.f, 1.f) * 255.f + 0.5f),
                          int(std::clamp(d.b, 0.f, 1.f) * 255.f + 0.5f));
        }
    }
    return out;
}

/// The heat-map's range: ±50 % relative block error at full colour (beyond it, saturated).
constexpr float ERROR_MAP_RANGE = 0.5f;

/// Diverging colour of a signed relative error: blue too dark, white right, red too bright
/// (an eye reads the sign from the hue and the size from the saturation).
QRgb errorColour(float e) {
    if (std::isnan(e))
        return qRgb(40, 42, 48);  // no object pixel: the viewport's background
    const float t = std::clamp(e / ERROR_MAP_RANGE, -1.f, 1.f);
    const float keep = 1.f - std::abs(t);  // the other two channels fade from white
    const int c = int(255.f * keep + 0.5f);
    return t >= 0.f ? qRgb(255, c, c) : qRgb(c, c, 255);
}

QImage errorMapImage(const bench::BlockErrorMap& map) {
    QImage out(map.width, map.height, QImage::Format_RGB32);
    for (int y = 0; y < map.height; ++y)
        for (int x = 0; x < map.width; ++x)
            out.setPixel(x, y, errorColour(map.at(x, y)));
    return out;
}

/// The legend under the heat-map: the colour ramp with its ends named.
QPixmap legendPixmap(int width) {
    QPixmap pm(width, 14);
    QPainter p(&pm);
    for (int x = 0; x < width; ++x) {
        const float e = ERROR_MAP_RANGE * (2.f * (x + 0.5f) / float(width) - 1.f);
        p.setPen(QColor::fromRgb(errorColour(e)));
        p.drawLine(x, 0, x, 13);
    }
    return pm;
}

}  // namespace

ReferencePanel::ReferencePanel(Document* doc, Viewport* viewport, QWidget* parent)
    : QWidget(parent), m_doc(doc), m_viewport(viewport) {
    // Two pages: the reference and the preview's error against it; the Auto plan's
    // run-time-vs-error chart.
    auto* outer = new QVBoxLayout(this);
    outer->setContentsMargins(0, 0, 0, 0);
    m_pages = new QTabWidget;
    m_pages->setObjectName(QStringLiteral("referencePages"));
    outer->addWidget(m_pages);
    auto* referencePage = new QWidget;
    auto* layout = new QVBoxLayout(referencePage);
    auto* form = new QFormLayout;
    m_width = new QSpinBox;
    m_width->setRange(32, 1920);
    m_width->setValue(160);
    m_width->setSuffix(tr(" px wide"));
    m_spp = new QSpinBox;
    m_spp->setRange(3, 1 << 16);
    m_spp->setValue(64);
    m_spp->setSuffix(tr(" spp"));
    form->addRow(tr("Image"), m_width);
    form->addRow(tr("Samples"), m_spp);
    layout->addLayout(form);
    m_startStop = new QPushButton(tr("Render reference"));
    layout->addWidget(m_startStop);
    m_progress = new QProgressBar;
    m_progress->setRange(0, 1);
    m_progress->setValue(0);
    layout->addWidget(m_progress);
    m_info = new QLabel(tr("Monte Carlo path tracer: the ground truth of every preview."));
    m_info->setWordWrap(true);
    layout->addWidget(m_info);
    // Drawn at the dock's size whenever the dock changes (not scaled once per pass), and
    // never wider than the dock lets it be.
    m_view = new QComboBox;
    m_view->setObjectName(QStringLiteral("referenceView"));
    m_view->addItems({tr("Reference"), tr("Preview at the reference's size"),
                      tr("Error map (preview vs reference)")});
    m_view->setToolTip(
        tr("The error map colours each 4×4-pixel block by the preview's relative "
           "error against the reference: red too bright, blue too dark."));
    layout->addWidget(m_view);
    m_accuracy = new QLabel(tr("Render a reference to see how accurate the preview is."));
    m_accuracy->setObjectName(QStringLiteral("referenceAccuracy"));
    m_accuracy->setWordWrap(true);
    m_accuracy->setTextInteractionFlags(Qt::TextSelectableByMouse);
    layout->addWidget(m_accuracy);
    // Drawn at the dock's size whenever the dock changes (not scaled once per pass), and
    // never wider than the dock lets it be. The error map's blocks stay sharp.
    m_picture = new ImageView(Qt::SmoothTransformation);
    m_picture->setObjectName(QStringLiteral("referencePicture"));
    m_picture->setMinimumSize(96, 72);
    layout->addWidget(m_picture, 1);
    m_legend = new QLabel;
    m_legend->setObjectName(QStringLiteral("referenceLegend"));
    m_legend->setText(
        tr("<table width='100%'><tr><td>−50 % (too dark)</td><td align='center'>0</td>"
           "<td align='right'>+50 % (too bright)</td></tr></table>"));
    auto* ramp = new QLabel;
    ramp->setPixmap(legendPixmap(240));
    ramp->setScaledContents(true);
    ramp->setMaximumHeight(14);
    auto* legendBox = new QWidget;
    auto* legendLayout = new QVBoxLayout(legendBox);
    legendLayout->setContentsMargins(0, 0, 0, 0);
    legendLayout->setSpacing(0);
    legendLayout->addWidget(ramp);
    legendLayout->addWidget(m_legend);
    legendBox->setVisible(false);
    layout->addWidget(legendBox);
    m_pages->addTab(referencePage, tr("Reference"));
    m_planChart = new PlanChart(m_doc, m_viewport, this);
    m_planChart->setObjectName(QStringLiteral("planChart"));
    m_pages->addTab(m_planChart, tr("Run time vs error"));
    connect(m_view, &QComboBox::currentIndexChanged, this, [this, legendBox](int index) {
        legendBox->setVisible(index == int(View::ErrorMap));
        if (index != int(View::Reference))
            compareWithPreview();
        refreshPicture();
    });
    // A converging preview changes its error: compare again, at most once a second, while the
    // preview or the error map is shown. Queued: the viewport emits from inside its paintGL,
    // where reading its image back (another makeCurrent/doneCurrent) would pull the context
    // from under the window's own paint.
    connect(
        m_viewport, &Viewport::frameRendered, this,
        [this] {
            if (m_view->currentIndex() != int(View::Reference) && !m_refMean.isEmpty() &&
                m_sinceCompare.elapsedMs() > 1000.0)
                compareWithPreview();
        },
        Qt::QueuedConnection);
    connect(m_startStop, &QPushButton::clicked, this, [this] {
        if (isRunning())
            stop();
        else
            start();
    });
}

ReferencePanel::~ReferencePanel() {
    if (m_thread) {
        m_cancel->store(true);
        m_thread->wait();
        delete m_thread;
    }
}

void ReferencePanel::showImage(const QImage& img) {
    m_image = img;
    refreshPicture();
}

void ReferencePanel::setView(View view) {
    m_view->setCurrentIndex(int(view));
}

void ReferencePanel::refreshPicture() {
    switch (View(m_view->currentIndex())) {
        case View::Reference:
            m_picture->setImage(m_image);
            break;
        case View::Preview:
            m_picture->setImage(m_previewImage);
            break;
        case View::ErrorMap:
            // Nearest: a block is one colour, its edges are the 4-pixel grid.
            m_picture->setImage(m_errorImage.isNull()
                                    ? QImage()
                                    : m_errorImage.scaled(m_errorImage.size() * 4,
                                                          Qt::IgnoreAspectRatio,
                                                          Qt::FastTransformation));
            break;
    }
}

bool ReferencePanel::compareWithPreview() {
    m_sinceCompare.reset();
    if (m_refMean.isEmpty()) {
        m_accuracy->setText(tr("Render a reference to see how accurate the preview is."));
        return false;
    }
    if (!viewIsReferenceView()) {
        m_accuracy->setText(
            tr("The view changed since the reference started: render it again "
               "to compare."));
        return false;
    }
    try {
        const ImageRgb preview =
            bench::resampleArea(m_viewport->linearImage(), m_refMean.width(), m_refMean.height());
        // The object's pixels: the reference's coverage when it is done, else those it has
        // lit so far (its background is black).
        std::vector<uint8_t> mask;
        if (!m_refCoverage.isEmpty()) {
            mask = bench::maskFromImage(m_refCoverage);
        } else {
            mask.resize(m_refMean.pixels().size());
            for (size_t i = 0; i < mask.size(); ++i)
                mask[i] = luminance(m_refMean.pixels()[i]) > 0.f;
        }
        const bench::ErrorReport r = bench::compareImages(
            preview, m_refMean, m_refVariance.isEmpty() ? nullptr : &m_refVariance, nullptr, &mask);
        const bench::BlockError& b = r.blocks[bench::ErrorReport::LUMINANCE];
        m_blockRelL1 = b.relL1;
        m_meanRatio = r.channels[bench::ErrorReport::LUMINANCE].meanRatio;
        m_errorImage = errorMapImage(bench::blockErrorMap(preview, m_refMean, &mask));
        m_previewImage = toDisplay(preview, m_exposure);
        const QString method = QString::fromStdString(m_viewport->stats().preview.method);
        QString text = tr("%1 against the reference: block error %2 %, mean ratio %3")
                           .arg(method)
                           .arg(100.0 * b.relL1, 0, 'f', 1)
                           .arg(m_meanRatio, 0, 'f', 3);
        text += r.hasNoiseFloor
                    ? tr(" (the reference's own noise: %1 %)").arg(100.0 * b.relL1Floor, 0, 'f', 1)
                    : tr(" (the reference is still refining)");
        m_accuracy->setText(text);
    } catch (const Error& e) {
        m_accuracy->setText(tr("No comparison: %1").arg(QString::fromUtf8(e.what())));
        return false;
    }
    refreshPicture();
    return true;
}

bool ReferencePanel::viewIsReferenceView() const {
    const OrbitCamera& cam = m_viewport->camera();
    return cam.eye() == m_refEye && cam.target == m_refTarget && cam.fovYDeg == m_refFovYDeg;
}

bool ReferencePanel::hasFinishedReferenceOfView() const {
    return !m_thread && !m_refMean.isEmpty() && !m_refCoverage.isEmpty() && viewIsReferenceView();
}

void ReferencePanel::showPage(int page) {
    m_pages->setCurrentIndex(page);
}

Scene ReferencePanel::frozenScene() const {
    return m_viewport->frozenSceneOfView(m_width->value());
}

Scene ReferencePanel::sceneAtView() const {
    Scene scene = m_doc->scene();
    m_viewport->applyViewTo(scene.camera, m_width->value());
    return scene;
}

void ReferencePanel::start() {
    if (m_thread || !m_doc->hasObject())
        return;
    // A frozen copy: painting may go on while the worker renders.
    Scene scene = frozenScene();
    const float exposure = std::exp2(m_viewport->renderSettings().exposureStops);
    const int spp = m_spp->value();
    m_refEye = scene.camera.position;  // the view the comparison needs
    m_refTarget = scene.camera.target;
    m_refFovYDeg = scene.camera.fovYDeg;
    m_exposure = exposure;
    m_refMean = m_refVariance = m_refCoverage = ImageRgb();
    m_previewImage = m_errorImage = QImage();

    m_cancel = std::make_shared<std::atomic<bool>>(false);
    auto cancel = m_cancel;
    auto error = std::make_shared<QString>();
    auto result = std::make_shared<reference::ReferenceImage>();
    QPointer<ReferencePanel> self(this);
    m_thread =
        QThread::create([scene = std::move(scene), spp, exposure, cancel, error, result, self] {
            reference::ReferenceOptions opt;
            opt.spp = spp;
            opt.cancel = cancel.get();
            opt.threads = std::max(1, QThread::idealThreadCount() - 1);  // keep a core for the UI
            opt.progress = [self](const reference::ReferenceProgress& p) {
                QMetaObject::invokeMethod(QCoreApplication::instance(), [self, p] {
                    if (!self)
                        return;
                    self->m_progress->setRange(0, p.maxSpp);
                    self->m_progress->setValue(p.spp);
                    self->m_info->setText(tr("%1 / %2 spp, RSE %3, %4 s")
                                              .arg(p.spp)
                                              .arg(p.maxSpp)
                                              .arg(double(p.rse), 0, 'g', 3)
                                              .arg(p.elapsedMs / 1000.0, 0, 'f', 1));
                });
            };
            opt.preview = [self, exposure](const ImageRgb& mean) {
                QImage img = toDisplay(mean, exposure);
                QMetaObject::invokeMethod(QCoreApplication::instance(), [self, img, mean] {
                    if (!self)
                        return;
                    self->m_refMean = mean;
                    self->showImage(img);
                    if (self->m_view->currentIndex() != int(View::Reference))
                        self->compareWithPreview();
                });
            };
            try {
                *result = reference::renderReference(scene, opt);
            } catch (const std::exception& ex) {
                *error = QString::fromUtf8(ex.what());
            }
        });
    connect(m_thread, &QThread::finished, this, [this, error, result, exposure] {
        m_thread->deleteLater();
        m_thread = nullptr;
        m_startStop->setText(tr("Render reference"));
        if (!error->isEmpty()) {
            m_info->setText(tr("Reference failed: %1").arg(*error));
        } else {
            if (!result->mean.isEmpty()) {
                m_refMean = result->mean;
                m_refVariance = result->variance;
                m_refCoverage = result->coverage;
                showImage(toDisplay(result->mean, exposure));
                compareWithPreview();
            }
            m_info->setText(tr("%1 spp in %2 s, RSE %3%4")
                                .arg(result->spp)
                                .arg(result->seconds, 0, 'f', 1)
                                .arg(double(result->rse), 0, 'g', 3)
                                .arg(result->cancelled ? tr(" (stopped)") : QString()));
        }
        Q_EMIT finished();
    });
    m_startStop->setText(tr("Stop"));
    m_progress->setRange(0, spp);
    m_progress->setValue(0);
    m_thread->start(QThread::LowPriority);
}

void ReferencePanel::setParameters(int width, int spp) {
    m_width->setValue(width);
    m_spp->setValue(spp);
}

void ReferencePanel::stop() {
    if (m_cancel)
        m_cancel->store(true);
}

}  // namespace lucent::app
