// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief "Seeing inside": an axis-aligned slice of any painted channel, colour-mapped
/// (viridis) with a legend in physical units.

#include <lucent/material/MaterialVolume.h>

#include <QImage>
#include <QWidget>

class QComboBox;
class QLabel;
class QSlider;

namespace lucent::app {

class Document;
class ImageView;

/// The slice image (one pixel per voxel, first in-plane axis to the right, second up), the
/// range of its values and the range its colour map spans.
struct SliceImage {
    QImage image;
    float minValue = 0.f, maxValue = 0.f;  ///< of the inside voxels
    /// The colour map's ends: the values' range, widened around its middle to at least 1 % of
    /// the values' magnitude (10⁻³ at least), so rounding noise is not stretched over the map.
    float mapMin = 0.f, mapMax = 0.f;
    bool nearlyUniform = false;  ///< the range was widened
};
/// @param axis 0 x, 1 y, 2 z; @param component MaterialVolume component 0..8; @param index
/// slice index along the axis (clamped). Outside voxels are drawn dark grey.
SliceImage renderSlice(const lucent::MaterialVolume& volume, int axis, int component, int index);

/// Viridis colour map (matplotlib; van der Walt & Smith 2015), t ∈ [0, 1].
QRgb viridis(float t);

class SliceView : public QWidget {
    Q_OBJECT
public:
    explicit SliceView(Document* doc, QWidget* parent = nullptr);
    /// Current slice image (for tests).
    [[nodiscard]] const QImage& image() const { return m_image; }
    void setSlice(int axis, int component, int index);

private:
    void refresh();
    Document* m_doc;
    QComboBox* m_axis;
    QComboBox* m_channel;
    QSlider* m_index;
    ImageView* m_picture;
    QLabel* m_legend;
    QLabel* m_range;
    QImage m_image;
};

}  // namespace lucent::app
