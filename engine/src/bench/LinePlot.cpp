// SPDX-License-Identifier: MIT
#include <lucent/bench/LinePlot.h>

#include <lucent/core/Error.h>

#include <algorithm>
#include <cmath>

namespace lucent::bench {

ImageRgb renderLinePlot(const LinePlot& plot) {
    const int W = plot.width, H = plot.height, margin = plot.margin;
    LUCENT_CHECK(!plot.curves.empty(), "line plot: no curve");
    LUCENT_CHECK(margin >= 0 && W - 2 * margin >= 2 && H - 2 * margin >= 2, "line plot: ", W, "x",
                 H, " px leaves no room inside margins of ", margin, " px");
    double yMax = 0.0;
    for (const LinePlot::Curve& c : plot.curves) {
        LUCENT_CHECK(c.values.size() >= 2, "line plot: a curve needs at least 2 samples");
        for (double v : c.values) {
            LUCENT_CHECK(std::isfinite(v), "line plot: a curve holds a non-finite value");
            yMax = std::max(yMax, v);
        }
    }
    if (!(yMax > 0.0))
        yMax = 1.0;
    const int plotW = W - 2 * margin, plotH = H - 2 * margin;
    ImageRgb img(W, H, Rgb(1.f));
    for (int x = margin; x <= W - margin; ++x)
        img.at(x, H - margin) = Rgb(0.f);
    for (int y = margin; y <= H - margin; ++y)
        img.at(margin, y) = Rgb(0.f);
    for (const LinePlot::Curve& c : plot.curves) {
        const size_t n = c.values.size();
        int prevY = -1;
        // One column per pixel of the plot's width; the curve sampled at the nearest sample.
        for (int i = 0; i <= plotW; ++i) {
            const size_t k = size_t(std::lround(double(i) / plotW * double(n - 1)));
            const double v = std::max(0.0, c.values[k]);
            const int y = H - margin - int(std::lround(v / yMax * (plotH - 1)));
            const int lo = prevY < 0 ? y : std::min(prevY, y);
            const int hi = prevY < 0 ? y : std::max(prevY, y);
            for (int yy = lo; yy <= hi; ++yy)
                for (int t = 0; t < 2; ++t)
                    img.at(std::min(W - 1, margin + i + t), std::clamp(yy, 0, H - 1)) = c.colour;
            prevY = y;
        }
    }
    return img;
}

}  // namespace lucent::bench
