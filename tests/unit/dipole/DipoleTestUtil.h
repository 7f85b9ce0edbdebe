// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Exact reference integrals and unbiasedness checks shared by the dipole image tests.

#include <lucent/core/Image.h>
#include <lucent/dipole/ImageSpace.h>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

namespace lucent::dipole::testutil {

/// ∫₀^R R_d(r) 2πr dr by Simpson in r = R u² (dense near the peak).
inline double radialIntegral(const DipoleProfile& p, double R) {
    if (!(R > 0.0))
        return 0.0;
    const int n = 200;
    double s = 0.0;
    for (int i = 0; i <= n; ++i) {
        const double u = double(i) / n, r = R * u * u;
        const double f = p.Rd(r) * 2 * M_PI * r * 2 * R * u;
        s += f * (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0));
    }
    return s / (3.0 * n);
}

/// Exact B(x_o) = ∫ R_d E dA for E = 1 on the box [x0,x1]×[y0,y1] (0 elsewhere): polar rays
/// from x_o, each meets the convex box in one interval [t0, t1].
inline double exactBox(const DipoleProfile& p, glm::dvec2 xo, double x0, double x1, double y0,
                       double y1) {
    const int rays = 2000;
    double sum = 0.0;
    for (int k = 0; k < rays; ++k) {
        const double phi = 2 * M_PI * (k + 0.5) / rays;
        const glm::dvec2 d(std::cos(phi), std::sin(phi));
        double t0 = 0.0, t1 = 1e30;
        const double lo[2] = {x0, y0}, hi[2] = {x1, y1};
        for (int a = 0; a < 2; ++a) {
            if (std::abs(d[a]) < 1e-15) {
                if (xo[a] < lo[a] || xo[a] > hi[a])
                    t1 = -1.0;
                continue;
            }
            double ta = (lo[a] - xo[a]) / d[a], tb = (hi[a] - xo[a]) / d[a];
            if (ta > tb)
                std::swap(ta, tb);
            t0 = std::max(t0, ta);
            t1 = std::min(t1, tb);
        }
        if (t1 > t0)
            sum += radialIntegral(p, t1) - radialIntegral(p, t0);
    }
    return sum / rays;  // (1/2π)∫dφ ∫ R_d 2πr dr
}

/// Compares the gathered exitance of channel c over a set of pixels with the exact value:
/// the mean difference must be within 4 standard errors of the per-pixel spread (the pixels
/// use distinct interleaved shifts), plus 1e-3 relative for float positions and quadrature.
inline void expectUnbiased(const GatherResult& g, const SurfaceBuffers& b,
                           const std::vector<glm::ivec2>& pixels,
                           const std::function<double(glm::dvec2, int)>& exact, int c) {
    double sum = 0.0, sum2 = 0.0, ref = 0.0;
    for (const auto& px : pixels) {
        const Point3f p = b.position[b.index(px.x, px.y)];
        const double e = exact({p.x, p.y}, c);
        const double d = double(g.exitance.at(px.x, px.y)[c]) - e;
        sum += d;
        sum2 += d * d;
        ref += e;
    }
    const double n = double(pixels.size()), mean = sum / n;
    const double se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / (n - 1));
    EXPECT_NEAR(mean, 0.0, 4 * se + 1e-3 * ref / n) << "channel " << c << " ref " << ref / n;
}

inline std::vector<glm::ivec2> block(int x0, int y0, int w, int h) {
    std::vector<glm::ivec2> v;
    for (int y = y0; y < y0 + h; ++y)
        for (int x = x0; x < x0 + w; ++x)
            v.push_back({x, y});
    return v;
}

}  // namespace lucent::dipole::testutil
