// SPDX-License-Identifier: MIT
#include <lucent/bench/LinePlot.h>
#include <lucent/core/Error.h>

#include <gtest/gtest.h>

#include <limits>

using namespace lucent;
using namespace lucent::bench;

namespace {

bool isColour(const Rgb& a, const Rgb& b) {
    return a.r == b.r && a.g == b.g && a.b == b.b;
}

}  // namespace

TEST(LinePlot, CurveRunsFromTheAxisToTheTopAndAxesAreBlack) {
    LinePlot plot;
    plot.width = 50;
    plot.height = 30;
    plot.margin = 5;
    const Rgb red(1.f, 0.f, 0.f);
    // A ramp 0 → 2: its first column sits on the x axis, its last one at the top row.
    plot.curves.push_back({{0.0, 1.0, 2.0}, red});
    const ImageRgb img = renderLinePlot(plot);
    ASSERT_EQ(img.width(), 50);
    ASSERT_EQ(img.height(), 30);
    EXPECT_TRUE(isColour(img.at(5, 30 - 5), red));             // x = 0: on the axis
    EXPECT_TRUE(isColour(img.at(45, 30 - 5 - 19), red));       // x = max: plotH − 1 above it
    EXPECT_TRUE(isColour(img.at(5, 10), Rgb(0.f)));            // the y axis
    EXPECT_TRUE(isColour(img.at(30, 25), Rgb(0.f)));           // the x axis, past the curve
    EXPECT_TRUE(isColour(img.at(2, 2), Rgb(1.f)));             // outside the margins: white
    EXPECT_TRUE(isColour(img.at(10, 30 - 5 - 19), Rgb(1.f)));  // above the ramp's start
}

TEST(LinePlot, RefusesWhatItCannotDraw) {
    LinePlot plot;
    EXPECT_THROW(renderLinePlot(plot), ValueError);  // no curve
    plot.curves.push_back({{1.0}, Rgb(0.f)});
    EXPECT_THROW(renderLinePlot(plot), ValueError);  // one sample
    plot.curves[0].values = {1.0, std::numeric_limits<double>::quiet_NaN()};
    EXPECT_THROW(renderLinePlot(plot), ValueError);
    plot.curves[0].values = {1.0, 2.0};
    plot.width = 10;
    plot.margin = 5;
    EXPECT_THROW(renderLinePlot(plot), ValueError);  // no room inside the margins
}
