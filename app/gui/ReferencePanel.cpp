// SPDX-License-Identifier: MIT
/// @file
/// @brief Reference dock: progressive path tracing off the UI thread.

#include "ReferencePanel.h"

#include "Document.h"
#include "ImageView.h"
#include "Viewport.h"

#include <lucent/reference/PathTracer.h>

#include <QFormLayout>
#include <QCoreApplication>
#include <QLabel>
#include <QPointer>
#include <QProgressBar>
#include <QPushButton>
#include <QSpinBox>
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

}  // namespace

ReferencePanel::ReferencePanel(Document* doc, Viewport* viewport, QWidget* parent)
    : QWidget(parent), m_doc(doc), m_viewport(viewport) {
    auto* layout = new QVBoxLayout(this);
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
    m_picture = new ImageView(Qt::SmoothTransformation);
    m_picture->setObjectName(QStringLiteral("referencePicture"));
    m_picture->setMinimumSize(96, 72);
    layout->addWidget(m_picture, 1);
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
    m_picture->setImage(img);
}

void ReferencePanel::start() {
    if (m_thread || !m_doc->hasObject())
        return;
    // A frozen copy: painting may go on while the worker renders.
    Scene scene = m_doc->scene();
    scene.objects[0].material = std::make_shared<MaterialVolume>(*m_doc->material());
    const OrbitCamera& cam = m_viewport->camera();
    scene.camera.position = cam.eye();
    scene.camera.target = cam.target;
    scene.camera.up = Vector3f(0.f, 1.f, 0.f);
    scene.camera.orthographic = false;
    scene.camera.fovYDeg = cam.fovYDeg;
    scene.camera.width = m_width->value();
    const double aspect = double(m_viewport->height()) / double(std::max(m_viewport->width(), 1));
    scene.camera.height = std::max(16, int(std::lround(m_width->value() * aspect)));
    const float exposure = std::exp2(m_viewport->renderSettings().exposureStops);
    const int spp = m_spp->value();

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
                QMetaObject::invokeMethod(QCoreApplication::instance(), [self, img] {
                    if (self)
                        self->showImage(img);
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
            if (!result->mean.isEmpty())
                showImage(toDisplay(result->mean, exposure));
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
