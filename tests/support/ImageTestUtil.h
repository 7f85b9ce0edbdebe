// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Whole-image extremes that tests compare against (tests/support/, on every test's
/// include path).

#include <lucent/core/Image.h>

#include <algorithm>
#include <cmath>

namespace lucent::test {

/// The largest channel value of `image`.
inline float largestValue(const ImageRgb& image) {
    float m = 0.f;
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < image.width(); ++x)
            m = std::max({m, image.at(x, y).r, image.at(x, y).g, image.at(x, y).b});
    return m;
}

/// The largest |a − b| over pixels and channels (images of the same size).
inline float largestDifference(const ImageRgb& a, const ImageRgb& b) {
    float d = 0.f;
    for (int y = 0; y < a.height(); ++y)
        for (int x = 0; x < a.width(); ++x)
            for (int c = 0; c < 3; ++c)
                d = std::max(d, std::abs(a.at(x, y)[c] - b.at(x, y)[c]));
    return d;
}

}  // namespace lucent::test
