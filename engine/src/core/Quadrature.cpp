// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/core/Quadrature.h>

#include <cmath>

namespace lucent {

QuadratureRule QuadratureRule::mappedTo(double a, double b) const {
    const double h = 0.5 * (b - a), m = 0.5 * (a + b);
    QuadratureRule r;
    r.x.resize(x.size());
    r.w.resize(w.size());
    for (size_t i = 0; i < x.size(); ++i) {
        r.x[i] = m + h * x[i];
        r.w[i] = h * w[i];
    }
    return r;
}

QuadratureRule gaussLegendre(int n) {
    LUCENT_CHECK(n >= 1 && n <= 1024, "gaussLegendre: node count must be in [1, 1024] (got ", n,
                 ")");
    QuadratureRule r;
    r.x.assign(size_t(n), 0.0);
    r.w.assign(size_t(n), 0.0);
    for (int i = 0; i < (n + 1) / 2; ++i) {
        // Tricomi's first guess of the i-th root from the top, then Newton on P_n, with P_n′
        // from the recurrence (P_n′ = n(z P_n − P_{n−1})/(z² − 1)).
        double z = std::cos(M_PI * (i + 0.75) / (n + 0.5));
        double dp = 0.0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = 0.0;
            for (int k = 1; k <= n; ++k) {
                const double p2 = p1;
                p1 = p0;
                p0 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p2) / k;
            }
            dp = n * (z * p0 - p1) / (z * z - 1.0);
            const double dz = p0 / dp;
            z -= dz;
            if (std::abs(dz) < 1e-15)
                break;
        }
        r.x[size_t(i)] = -z;
        r.x[size_t(n - 1 - i)] = z;
        r.w[size_t(i)] = r.w[size_t(n - 1 - i)] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
    return r;
}

}  // namespace lucent
