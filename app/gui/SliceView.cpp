// SPDX-License-Identifier: MIT
/// @file
/// @brief Slice view of the painted volume.

#include "SliceView.h"

#include "Document.h"
#include "ImageView.h"

#include <QComboBox>
#include <QHBoxLayout>
#include <QLabel>
#include <QSlider>
#include <QVBoxLayout>

#include <array>

namespace lucent::app {

QRgb viridis(float t) {
    // Nine samples of matplotlib's viridis, linearly interpolated.
    static constexpr std::array<std::array<float, 3>, 9> K = {{{0.267f, 0.005f, 0.329f},
                                                               {0.283f, 0.141f, 0.458f},
                                                               {0.254f, 0.265f, 0.530f},
                                                               {0.207f, 0.372f, 0.553f},
                                                               {0.164f, 0.471f, 0.558f},
                                                               {0.128f, 0.567f, 0.551f},
                                                               {0.135f, 0.659f, 0.518f},
                                                               {0.478f, 0.821f, 0.318f},
                                                               {0.993f, 0.906f, 0.144f}}};
    t = std::clamp(std::isfinite(t) ? t : 0.f, 0.f, 1.f) * 8.f;
    const int i = std::min(int(t), 7);
    const float f = t - float(i);
    auto ch = [&](int c) {
        return int(255.f * (K[size_t(i)][size_t(c)] * (1.f - f) + K[size_t(i) + 1][size_t(c)] * f) +
                   0.5f);
    };
    return qRgb(ch(0), ch(1), ch(2));
}

SliceImage renderSlice(const MaterialVolume& volume, int axis, int component, int index) {
    SliceImage out;
    const int res = volume.resolution();
    if (res <= 0)
        return out;
    axis = std::clamp(axis, 0, 2);
    component = std::clamp(component, 0, MaterialVolume::COMPONENTS - 1);
    index = std::clamp(index, 0, res - 1);
    const int ua = (axis + 1) % 3, va = (axis + 2) % 3;  // in-plane axes (right, up)
    std::vector<float> values(size_t(res) * res, 0.f);
    std::vector<uint8_t> inside(size_t(res) * res, 0);
    float lo = INF, hi = -INF;
    for (int v = 0; v < res; ++v)
        for (int u = 0; u < res; ++u) {
            Coord c;
            c[axis] = index;
            c[ua] = u;
            c[va] = v;
            if (!volume.isInside(c))
                continue;
            const float x = volume.component(c, component);
            values[size_t(v) * res + u] = x;
            inside[size_t(v) * res + u] = 1;
            lo = std::min(lo, x);
            hi = std::max(hi, x);
        }
    if (lo > hi)
        lo = hi = 0.f;
    out.minValue = lo;
    out.maxValue = hi;
    // The colour map spans at least 1 % of the values' magnitude (and 10⁻³ absolute): a slice
    // that is uniform up to rounding (0.9999 … 1 mm⁻¹) shows as one colour, not as the whole
    // map stretched over float noise.
    const float minSpan = std::max(1e-2f * std::max(std::abs(lo), std::abs(hi)), 1e-3f);
    float mapLo = lo, mapHi = hi;
    if (hi - lo < minSpan) {
        const float mid = 0.5f * (lo + hi);
        mapLo = mid - 0.5f * minSpan;
        mapHi = mid + 0.5f * minSpan;
        out.nearlyUniform = true;
    }
    out.mapMin = mapLo;
    out.mapMax = mapHi;
    out.image = QImage(res, res, QImage::Format_RGB32);
    lo = mapLo;
    const float span = mapHi - mapLo;
    for (int v = 0; v < res; ++v) {
        auto* row = reinterpret_cast<QRgb*>(out.image.scanLine(res - 1 - v));  // +v up
        for (int u = 0; u < res; ++u) {
            const size_t i = size_t(v) * res + u;
            row[u] = inside[i] ? viridis((values[i] - lo) / span) : qRgb(40, 40, 44);
        }
    }
    return out;
}

SliceView::SliceView(Document* doc, QWidget* parent) : QWidget(parent), m_doc(doc) {
    auto* layout = new QVBoxLayout(this);
    auto* row = new QHBoxLayout;
    m_axis = new QComboBox;
    m_axis->addItems({tr("X slice"), tr("Y slice"), tr("Z slice")});
    m_axis->setCurrentIndex(2);
    m_channel = new QComboBox;
    const char* names[] = {"σt R", "σt G", "σt B", "σs′ R", "σs′ G", "σs′ B", "g R", "g G", "g B"};
    for (const char* n : names)
        m_channel->addItem(QString::fromUtf8(n));
    row->addWidget(m_axis);
    row->addWidget(m_channel);
    layout->addLayout(row);
    m_index = new QSlider(Qt::Horizontal);
    layout->addWidget(m_index);
    m_picture = new ImageView(Qt::FastTransformation);  // voxels stay square
    m_picture->setMinimumSize(96, 96);
    layout->addWidget(m_picture, 1);
    m_legend = new QLabel;
    m_legend->setFixedHeight(14);
    m_legend->setScaledContents(true);
    QImage bar(256, 1, QImage::Format_RGB32);
    for (int i = 0; i < 256; ++i)
        bar.setPixel(i, 0, viridis(float(i) / 255.f));
    m_legend->setPixmap(QPixmap::fromImage(bar));
    layout->addWidget(m_legend);
    m_range = new QLabel;
    layout->addWidget(m_range);
    connect(m_axis, &QComboBox::currentIndexChanged, this, [this] { refresh(); });
    connect(m_channel, &QComboBox::currentIndexChanged, this, [this] { refresh(); });
    connect(m_index, &QSlider::valueChanged, this, [this] { refresh(); });
    connect(m_doc, &Document::materialEdited, this, [this] { refresh(); });
    connect(m_doc, &Document::sceneReplaced, this, [this] {
        if (const MaterialVolume* v = m_doc->material()) {
            m_index->setRange(0, v->resolution() - 1);
            m_index->setValue(v->resolution() / 2);
        }
        refresh();
    });
    if (const MaterialVolume* v = m_doc->material()) {
        m_index->setRange(0, v->resolution() - 1);
        m_index->setValue(v->resolution() / 2);
    }
    refresh();
}

void SliceView::setSlice(int axis, int component, int index) {
    m_axis->setCurrentIndex(axis);
    m_channel->setCurrentIndex(component);
    m_index->setValue(index);
    refresh();
}

void SliceView::refresh() {
    const MaterialVolume* v = m_doc->material();
    if (!v) {
        m_picture->setImage(QImage());
        return;
    }
    const SliceImage s =
        renderSlice(*v, m_axis->currentIndex(), m_channel->currentIndex(), m_index->value());
    m_image = s.image;
    m_picture->setImage(m_image);
    const bool isG = m_channel->currentIndex() >= 6;
    m_range->setText(tr("slice %1 of %2   %3 … %4 %5%6")
                         .arg(m_index->value())
                         .arg(v->resolution())
                         .arg(double(s.minValue), 0, 'g', 4)
                         .arg(double(s.maxValue), 0, 'g', 4)
                         .arg(isG ? QString() : QStringLiteral("mm⁻¹"))
                         .arg(s.nearlyUniform ? tr(" (uniform within 1 %)") : QString()));
}

}  // namespace lucent::app
