// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Exact importance sampling of the dipole's R_d(r)·r (Mertens et al. 2005 §4).
///
///     DipoleSampler s(DipoleProfile::jensen(0.0021, 2.19, 1.3));
///     double r = s.sample(u1, u2);        // mm, distributed as R_d(r)·r / ρ
///     double pdf = s.pdfArea(r);           // mm⁻², = R_d(r)/ρ for Jensen's dipole
///
/// For the better dipole the same sampler draws from the flux term's shape (with the better
/// dipole's σ_tr, z_r, z_v); callers weight by R_d/pdf, so the estimate stays unbiased.

#include <lucent/dipole/Profiles.h>

#include <limits>

namespace lucent::dipole {

/// Solves σz(u − 1) + log u + log(1 − ξ) = 0 for u ≥ 1 (Mertens et al. 2005 §4) by a bracketed,
/// safeguarded Newton iteration on v = log u (convex, increasing; converges for every
/// ξ ∈ [0, 1) and σz ≥ 0). @return log u. @param iterations receives the iteration count.
/// @throw ValueError if σz < 0 or non-finite, or ξ ∉ [0, 1).
double solveLogU(double sigmaZ, double xi, int* iterations = nullptr);

/// Radius of one source drawn from its normalised z(1+σd)e^{−σd}/d³·r: r = z√(u² − 1), mm.
double sampleSourceRadius(double sigma, double z, double xi);
/// P(radius ≤ r) for one source: 1 − (z/d) e^{−σ(d − z)}, d = √(r² + z²).
double sourceRadiusCdf(double sigma, double z, double r);

/// Mixture of the real and virtual sources, chosen with probability ∝ e^{−σz} (Mertens et al. 2005
/// §4).
class DipoleSampler {
public:
    DipoleSampler() = default;
    explicit DipoleSampler(const DipoleProfile& p);

    /// @param xiSource chooses the source; @param xiRadius ∈ [0, 1) the radius. @return r, mm.
    [[nodiscard]] double sample(double xiSource, double xiRadius) const;
    /// Density per unit area (mm⁻²) of the sampled point on the plane at radius r (uniform φ).
    [[nodiscard]] double pdfArea(double r) const;
    /// P(radius ≤ r).
    [[nodiscard]] double cdf(double r) const;
    /// Radius with cdf(r) = q, q ∈ [0, 1). Bisection on cdf.
    [[nodiscard]] double quantile(double q) const;
    [[nodiscard]] double probabilityReal() const { return m_pReal; }
    [[nodiscard]] bool isValid() const { return m_zr > 0.0; }

    /// The same sampler restricted to r ≤ maxRadius (mm; ≤ 0 or ∞: unrestricted): the mixture
    /// is conditioned on r ≤ maxRadius, i.e. source s is chosen with P(s)·F_s(R)/F(R) and its
    /// radius by inverting F_s on [0, F_s(R)); pdfArea() and cdf() are the renormalised
    /// pdf/F(R) and F(min(r, R))/F(R), so R/pdf estimators stay unbiased for ∫_{r ≤ R}.
    [[nodiscard]] DipoleSampler truncated(double maxRadius) const;
    /// mm; +∞ when not truncated.
    [[nodiscard]] double maxRadius() const { return m_maxRadius; }
    /// F(maxRadius) of the untruncated mixture: the probability mass the window keeps (1 when
    /// not truncated).
    [[nodiscard]] double keptMass() const { return m_mass; }

private:
    double m_sigma = 0.0, m_zr = 0.0, m_zv = 0.0, m_pReal = 1.0;
    // Truncation: per-source F_s(R) and the mass F(R) = P(real)F_r(R) + P(virtual)F_v(R).
    double m_maxRadius = std::numeric_limits<double>::infinity(), m_cdfReal = 1.0,
           m_cdfVirtual = 1.0, m_mass = 1.0;
    double m_pRealKept = 1.0;  ///< P(real | r ≤ R)
};

}  // namespace lucent::dipole
