// SPDX-License-Identifier: MIT
/// @file
/// @brief ImageView: an image drawn at the widget's size.

#include "ImageView.h"

#include <QPainter>

namespace lucent::app {

ImageView::ImageView(Qt::TransformationMode mode, QWidget* parent) : QWidget(parent), m_mode(mode) {
    setSizePolicy(QSizePolicy::Expanding, QSizePolicy::Expanding);
}

void ImageView::setImage(const QImage& image) {
    m_image = image;
    update();
}

QRect ImageView::imageRect() const {
    if (m_image.isNull())
        return {};
    const QSize s = m_image.size().scaled(size(), Qt::KeepAspectRatio);
    return {QPoint((width() - s.width()) / 2, (height() - s.height()) / 2), s};
}

QSize ImageView::sizeHint() const {
    return {160, 120};
}

void ImageView::paintEvent(QPaintEvent*) {
    QPainter p(this);
    p.fillRect(rect(), QColor(40, 40, 44));
    if (m_image.isNull())
        return;
    p.setRenderHint(QPainter::SmoothPixmapTransform, m_mode == Qt::SmoothTransformation);
    p.drawImage(imageRect(), m_image);
}

}  // namespace lucent::app
