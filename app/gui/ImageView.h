// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief A widget that shows an image scaled to its own size, aspect kept, centred on a dark
/// background. Unlike a QLabel pixmap, the image follows the widget when its dock is resized
/// and never sets the widget's size: a large image cannot lock a dock's width.
///
///     auto* view = new ImageView(Qt::SmoothTransformation);
///     view->setImage(img);  // repainted at the widget's size from now on

#include <QImage>
#include <QWidget>

namespace lucent::app {

class ImageView : public QWidget {
    Q_OBJECT
public:
    /// @param mode Qt::FastTransformation keeps voxels square (slices); Qt::SmoothTransformation
    ///        filters (renders).
    explicit ImageView(Qt::TransformationMode mode, QWidget* parent = nullptr);
    void setImage(const QImage& image);
    [[nodiscard]] const QImage& image() const { return m_image; }
    /// Where the image is drawn in widget coordinates (empty without an image).
    [[nodiscard]] QRect imageRect() const;
    /// Small, whatever the image: the layout decides the size.
    [[nodiscard]] QSize sizeHint() const override;

protected:
    void paintEvent(QPaintEvent* e) override;

private:
    QImage m_image;
    Qt::TransformationMode m_mode;
};

}  // namespace lucent::app
