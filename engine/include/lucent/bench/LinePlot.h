// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief A plain line chart rendered to an image, for tools that write a PNG beside their
/// numbers (`lucent-cli profile --plot`): no labels or ticks, the numbers are printed instead.
///
///     LinePlot plot;
///     plot.curves = {{redValues, Rgb(0.85f, 0.1f, 0.1f)}, {greenValues, ...}};
///     writePng(renderLinePlot(plot), "profile.png");

#include <lucent/core/Image.h>

#include <vector>

namespace lucent::bench {

/// Curves over a shared, evenly spaced x axis: sample i of every curve is at
/// x = i / (samples − 1) of the plot's width. y from 0 (the x axis) to the largest value of
/// all curves (the top).
struct LinePlot {
    struct Curve {
        std::vector<double> values;  ///< ≥ 2 samples, finite
        Rgb colour;
    };
    std::vector<Curve> curves;
    int width = 800, height = 500;  ///< pixels
    int margin = 40;                ///< pixels between the image edge and the axes
};

/// White canvas, black axes along the bottom and the left, each curve a 2-pixel-wide polyline
/// (vertical runs filled, so steep parts stay connected). @throw ValueError on an empty plot, a
/// curve with fewer than 2 samples or a non-finite one, or a size with no room inside the margins.
ImageRgb renderLinePlot(const LinePlot& plot);

}  // namespace lucent::bench
