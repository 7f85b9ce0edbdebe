// SPDX-License-Identifier: MIT
/// @file
/// @brief Exact importance sampling of the dipole profile (Mertens et al. 2005 §4).

#include <lucent/dipole/Sampling.h>

#include <lucent/core/Error.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace lucent::dipole {
namespace {
constexpr double PI_D = 3.14159265358979323846;
}

double solveLogU(double sigmaZ, double xi, int* iterations) {
    LUCENT_CHECK(std::isfinite(sigmaZ) && sigmaZ >= 0.0,
                 "solveLogU: sigma*z must be finite and >= 0 (got ", sigmaZ, ")");
    LUCENT_CHECK(xi >= 0.0 && xi < 1.0, "solveLogU: xi must be in [0, 1) (got ", xi, ")");
    if (iterations)
        *iterations = 0;
    // With v = log u the equation reads g(v) = σz(e^v − 1) + v − L = 0, L = −log(1 − ξ) ≥ 0.
    const double L = -std::log1p(-xi);
    if (L <= 0.0)
        return 0.0;
    const double c = sigmaZ;
    if (c == 0.0)
        return L;  // σ = 0: log u = L exactly
    // Bracket: g(0) = −L ≤ 0; g(L) ≥ 0 and g(log(1 + L/c)) ≥ 0 since both other terms are ≥ 0.
    double lo = 0.0, hi = std::min(L, std::log1p(L / c));
    const auto g = [&](double v) { return c * std::expm1(v) + v - L; };
    // g is convex and increasing: Newton from the upper end decreases monotonically onto the
    // root. The bracket still guards against round-off (bisection when a step leaves it).
    double v = hi;
    for (int it = 1; it <= 200; ++it) {
        if (iterations)
            *iterations = it;
        const double gv = g(v);
        if (gv == 0.0)
            return v;
        if (gv > 0.0)
            hi = v;
        else
            lo = v;
        double next = v - gv / (c * std::exp(v) + 1.0);
        if (!(next > lo && next < hi))
            next = 0.5 * (lo + hi);
        if (std::abs(next - v) <= 4.0 * std::numeric_limits<double>::epsilon() * std::abs(v) ||
            hi - lo <= 4.0 * std::numeric_limits<double>::epsilon() * hi)
            return next;
        v = next;
    }
    return v;
}

double sampleSourceRadius(double sigma, double z, double xi) {
    const double v = solveLogU(sigma * z, xi);
    // r = z√(u² − 1) = z√(e^{2v} − 1), with expm1 for small v.
    return z * std::sqrt(std::expm1(2.0 * v));
}

double sourceRadiusCdf(double sigma, double z, double r) {
    const double d = std::sqrt(r * r + z * z);
    // ∫_z^d (1+σt)e^{−σt}/t² dt / (e^{−σz}/z) = 1 − (z/d)e^{−σ(d−z)} (Mertens et al. 2005 Eq. 6–7).
    return 1.0 - (z / d) * std::exp(-sigma * (d - z));
}

DipoleSampler::DipoleSampler(const DipoleProfile& p) {
    if (p.zr() <= 0.0)
        return;
    m_sigma = p.sigmaTr();
    m_zr = p.zr();
    m_zv = p.zv();
    // P(real) = e^{−σz_r}/(e^{−σz_r} + e^{−σz_v}) = 1/(1 + e^{−σ(z_v − z_r)}).
    m_pReal = 1.0 / (1.0 + std::exp(-m_sigma * (m_zv - m_zr)));
    m_pRealKept = m_pReal;
}

DipoleSampler DipoleSampler::truncated(double maxRadius) const {
    DipoleSampler t = *this;
    t.m_maxRadius = std::numeric_limits<double>::infinity();
    t.m_cdfReal = t.m_cdfVirtual = t.m_mass = 1.0;
    t.m_pRealKept = m_pReal;
    if (!isValid() || !(maxRadius > 0.0) || !std::isfinite(maxRadius))
        return t;
    // Conditioning the two-source mixture of Mertens et al. 2005 §4 on r ≤ R: with F_s(R) of Eq.
    // 6–7, P(s | r ≤ R) = P(s)F_s(R)/F(R) and r | s has the cdf F_s(r)/F_s(R) on [0, R].
    t.m_maxRadius = maxRadius;
    t.m_cdfReal = sourceRadiusCdf(m_sigma, m_zr, maxRadius);
    t.m_cdfVirtual = sourceRadiusCdf(m_sigma, m_zv, maxRadius);
    t.m_mass = m_pReal * t.m_cdfReal + (1.0 - m_pReal) * t.m_cdfVirtual;
    if (!(t.m_mass > 0.0)) {
        t.m_zr = 0.0;  // nothing within R (cannot happen for R > 0, kept as a guard): invalid
        return t;
    }
    t.m_pRealKept = m_pReal * t.m_cdfReal / t.m_mass;
    return t;
}

double DipoleSampler::sample(double xiSource, double xiRadius) const {
    const bool real = xiSource < m_pRealKept;
    const double z = real ? m_zr : m_zv;
    // Inverting F_s on [0, F_s(R)): ξ′ = ξ·F_s(R) (F_s(R) = 1 when not truncated).
    const double xi =
        std::clamp(xiRadius, 0.0, std::nextafter(1.0, 0.0)) * (real ? m_cdfReal : m_cdfVirtual);
    return std::min(sampleSourceRadius(m_sigma, z, xi), m_maxRadius);
}

double DipoleSampler::pdfArea(double r) const {
    if (!isValid() || r > m_maxRadius)
        return 0.0;
    // Each source's normalised area density z(1+σd)e^{−σ(d−z)}/(2πd³) (∫ over the plane = 1).
    const auto g = [&](double z) {
        const double d = std::sqrt(r * r + z * z);
        if (!(d < 1e100) || m_sigma * (d - z) > 700.0)
            return 0.0;  // underflowed
        return z * (1.0 + m_sigma * d) * std::exp(-m_sigma * (d - z)) / (2.0 * PI_D * d * d * d);
    };
    return (m_pReal * g(m_zr) + (1.0 - m_pReal) * g(m_zv)) / m_mass;
}

double DipoleSampler::cdf(double r) const {
    if (!isValid())
        return 0.0;
    r = std::min(r, m_maxRadius);
    return std::min(1.0, (m_pReal * sourceRadiusCdf(m_sigma, m_zr, r) +
                          (1.0 - m_pReal) * sourceRadiusCdf(m_sigma, m_zv, r)) /
                             m_mass);
}

double DipoleSampler::quantile(double q) const {
    LUCENT_CHECK(q >= 0.0 && q < 1.0, "DipoleSampler::quantile: q must be in [0, 1)");
    if (!isValid() || q == 0.0)
        return 0.0;
    // The virtual source's quantile bounds the untruncated mixture's from above (its cdf is
    // smaller); with a window it is a first guess, widened up to maxRadius until it brackets q.
    double lo = 0.0, hi = sampleSourceRadius(m_sigma, m_zv, q * m_cdfVirtual) + m_zv;
    hi = std::min(hi, m_maxRadius);
    while (cdf(hi) < q && hi < m_maxRadius)
        hi = std::min(2.0 * hi, m_maxRadius);
    for (int i = 0; i < 200 && hi - lo > 1e-14 * hi; ++i) {
        const double m = 0.5 * (lo + hi);
        (cdf(m) < q ? lo : hi) = m;
    }
    return 0.5 * (lo + hi);
}

}  // namespace lucent::dipole
