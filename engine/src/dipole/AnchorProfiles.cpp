// SPDX-License-Identifier: MIT
/// @file
/// @brief Christensen–Burley normalised diffusion and photon beam diffusion as radial anchors
/// (AnchorProfiles.h; docs/methods/dipole.md §4b).

#include <lucent/dipole/AnchorProfiles.h>

#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/core/Quadrature.h>
#include <lucent/dipole/HalfSpace.h>
#include <lucent/dipole/Profiles.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace lucent::dipole {
namespace {
constexpr double PI_D = 3.14159265358979323846;
constexpr double SIGMA_MAX = 1e6;  // mm⁻¹, as DipoleProfile

void checkMedium(double sigma_a, double sigma_s, double eta, const char* who) {
    LUCENT_CHECK(std::isfinite(sigma_a) && sigma_a >= 0.0 && sigma_a <= SIGMA_MAX &&
                     std::isfinite(sigma_s) && sigma_s >= 0.0 && sigma_s <= SIGMA_MAX,
                 who, ": need 0 <= sigma_a, sigma_s' <= 1e6 mm^-1, finite (got ", sigma_a, ", ",
                 sigma_s, ")");
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0, who,
                 ": eta must be in [1, 3] (got ", eta, ")");
}

/// Gauss–Legendre nodes per panel of the composite rules below.
const QuadratureRule& panelRule() {
    static const QuadratureRule rule = gaussLegendre(8);
    return rule;
}

/// ∫_a^b f by composite Gauss–Legendre on `panels` panels uniform in log(x) (a > 0).
template <class F>
double integrateLog(F&& f, double a, double b, int panels) {
    const QuadratureRule& g = panelRule();
    const double la = std::log(a), step = (std::log(b) - la) / panels;
    double sum = 0.0;
    for (int p = 0; p < panels; ++p) {
        const double l0 = la + p * step;
        for (size_t i = 0; i < g.x.size(); ++i) {
            // g is on [−1, 1]: node ↦ l0 + step (x + 1)/2, weight step/2; dx = x dl.
            const double l = l0 + 0.5 * step * (g.x[i] + 1.0);
            const double x = std::exp(l);
            sum += 0.5 * step * g.w[i] * x * f(x);
        }
    }
    return sum;
}
}  // namespace

// ---------------------------------------------------------------------------------------------
// Christensen & Burley 2015

double burleySearchlightScale(double surfaceAlbedo) {
    LUCENT_CHECK(std::isfinite(surfaceAlbedo) && surfaceAlbedo >= 0.0 && surfaceAlbedo <= 1.0,
                 "burleySearchlightScale: the surface albedo must be in [0, 1] (got ",
                 surfaceAlbedo, ")");
    const double a = std::abs(surfaceAlbedo - 0.8);
    return 1.85 - surfaceAlbedo + 7.0 * a * a * a;  // Christensen & Burley 2015 Eq. 5
}

BurleyProfile::BurleyProfile(double surfaceAlbedo, double d) : m_A(surfaceAlbedo), m_d(d) {
    LUCENT_CHECK(std::isfinite(surfaceAlbedo) && surfaceAlbedo >= 0.0 && surfaceAlbedo <= 1.0,
                 "BurleyProfile: the surface albedo must be in [0, 1] (got ", surfaceAlbedo, ")");
    LUCENT_CHECK(std::isfinite(d) && d > 0.0, "BurleyProfile: d must be finite and > 0 mm (got ", d,
                 ")");
}

BurleyProfile BurleyProfile::searchlight(double sigma_a, double sigma_s, double eta) {
    checkMedium(sigma_a, sigma_s, eta, "BurleyProfile::searchlight");
    const double st = sigma_a + sigma_s;
    if (!(st > 0.0) || !(sigma_s > 0.0))
        return {};
    const double A = halfSpaceReflectance(sigma_s / st, eta);
    return {A, 1.0 / (st * burleySearchlightScale(A))};
}

double BurleyProfile::R(double r) const {
    if (m_A <= 0.0)
        return 0.0;
    r = std::abs(r);
    if (r == 0.0)
        return std::numeric_limits<double>::infinity();
    return m_A * (std::exp(-r / m_d) + std::exp(-r / (3.0 * m_d))) / (8.0 * PI_D * m_d * r);
}

double BurleyProfile::reflectanceBeyond(double radius) const {
    radius = std::max(0.0, radius);
    return m_A * (0.25 * std::exp(-radius / m_d) + 0.75 * std::exp(-radius / (3.0 * m_d)));
}

// ---------------------------------------------------------------------------------------------
// Photon beam diffusion (Habel, Christensen & Jarosz 2013)

PhotonBeamProfile::PhotonBeamProfile(double sigma_a, double sigma_s, double eta)
    : m_sigmaS(sigma_s), m_sigmaT(sigma_a + sigma_s), m_eta(eta) {
    checkMedium(sigma_a, sigma_s, eta, "PhotonBeamProfile");
    if (isZero())
        return;
    const Boundary b = Boundary::of(eta);
    // d'Eon 2012, as DipoleProfile::better (Profiles.h).
    m_D = (2.0 * sigma_a + sigma_s) / (3.0 * m_sigmaT * m_sigmaT);
    m_sigmaTr = std::sqrt(sigma_a / m_D);
    const double A = (1.0 + 3.0 * b.c2) / (1.0 - 2.0 * b.c1);
    m_zb2 = 4.0 * A * m_D;
    m_cPhi = 0.25 * (1.0 - 2.0 * b.c1);
    m_cE = 0.5 * (1.0 - 3.0 * b.c2);
}

double PhotonBeamProfile::multiple(double r) const {
    if (isZero())
        return 0.0;
    r = std::abs(r);
    const double ell = 1.0 / m_sigmaT, s = m_sigmaTr;
    // The better dipole's point source at depth t (per unit power), integrated against Q(t).
    const auto pointSource = [&](double t) {
        const double zr = t, zv = t + m_zb2;
        const double dr = std::sqrt(r * r + zr * zr), dv = std::sqrt(r * r + zv * zv);
        const double er = std::exp(-s * dr), ev = std::exp(-s * dv);
        const double flux = (zr * (1.0 + s * dr) * er / (dr * dr * dr) +
                             zv * (1.0 + s * dv) * ev / (dv * dv * dv)) /
                            (4.0 * PI_D);
        const double fluence = (er / dr - ev / dv) / (4.0 * PI_D * m_D);
        return m_sigmaS * std::exp(-m_sigmaT * t) * (m_cE * flux + m_cPhi * fluence);
    };
    // The integrand peaks at t ≈ r near the surface (the real source's 1/d³): start three
    // decades below min(r, ℓ), stop where Q has fallen by e^{−40}; four panels per decade.
    const double tMin = 1e-3 * std::max(std::min(r, ell), 1e-9 * ell), tMax = 40.0 * ell;
    const int panels = std::max(8, int(std::ceil(4.0 * std::log10(tMax / tMin))));
    // Below tMin: Q ≈ σs′ and the point source is smooth in t there (d ≥ r), so a midpoint
    // estimate suffices (it is < 10⁻³ of the whole for r ≥ tMin·10³).
    return integrateLog(pointSource, tMin, tMax, panels) + tMin * pointSource(0.5 * tMin);
}

double PhotonBeamProfile::single(double r) const {
    if (isZero())
        return 0.0;
    r = std::abs(r);
    if (r == 0.0)
        return std::numeric_limits<double>::infinity();
    // With u = √((1 + μ)/(1 − μ)) ∈ [1, ∞) (μ = (u² − 1)/(u² + 1)) the integral of the header
    // becomes ∫ T(μ(u)) e^{−x u} 2(u² − 1)/(u² + 1)² du, x = σt′ r: smooth in log(u). Directions
    // below the critical angle (μ < μ_c) are totally reflected: start at u_c.
    const double x = m_sigmaT * r;
    const double muC = m_eta > 1.0 ? std::sqrt(1.0 - 1.0 / (m_eta * m_eta)) : 0.0;
    const double uC = std::max(1.0 + 1e-12, std::sqrt((1.0 + muC) / (1.0 - muC)));
    const double uMax = uC + 60.0 / x;  // e^{−60} of the integrand's value at u_c
    const auto f = [&](double u) {
        const double u2 = u * u;
        const double mu = (u2 - 1.0) / (u2 + 1.0);
        const double T = 1.0 - fresnelDielectric(mu, 1.0 / m_eta);
        return T * std::exp(-x * (u - uC)) * 2.0 * (u2 - 1.0) / ((u2 + 1.0) * (u2 + 1.0));
    };
    // T rises like √(u − u_c) from the critical angle: near it substitute u = u_c + v²
    // (du = 2v dv), which makes the integrand smooth (e^{−x v²}: v up to 8/√x at most);
    // beyond, panels uniform in log u.
    const QuadratureRule& g = panelRule();
    const double vMax = std::min(1.0, 8.0 / std::sqrt(x));
    double integral = 0.0;
    for (int p = 0; p < 4; ++p)
        for (size_t i = 0; i < g.x.size(); ++i) {
            const double v = 0.25 * vMax * (p + 0.5 * (g.x[i] + 1.0));
            integral += 0.125 * vMax * g.w[i] * 2.0 * v * f(uC + v * v);
        }
    const double uFar = uC + vMax * vMax;
    if (uMax > uFar) {
        const int panels = std::max(8, int(std::ceil(6.0 * std::log10(uMax / uFar))));
        integral += integrateLog(f, uFar, uMax, panels);
    }
    integral *= std::exp(-x * uC);
    return (m_sigmaS / m_sigmaT) * m_sigmaT / (4.0 * PI_D * r) * integral;
}

double PhotonBeamProfile::multipleTotal() const {
    if (isZero())
        return 0.0;
    const double s = m_sigmaTr, z = m_zb2;
    const double eV = std::exp(-s * z);
    // C_φ/(2Dσ)(1 − e^{−σz}) → C_φ z/(2D) as σ → 0 (−expm1 keeps the small-σ digits).
    const double phiTerm = s > 0.0 ? -std::expm1(-s * z) / (2.0 * m_D * s) : z / (2.0 * m_D);
    return m_sigmaS / (m_sigmaT + s) * (0.5 * m_cE * (1.0 + eV) + m_cPhi * phiTerm);
}

double PhotonBeamProfile::singleTotal() const {
    if (isZero())
        return 0.0;
    // α′/2 ∫ T(μ) μ/(1 + μ) dμ over [μ_c, 1] (T = 0 below the critical cosine). T rises like
    // √(μ − μ_c): with μ = μ_c + (1 − μ_c) v² the integrand is smooth in v.
    const double muC = m_eta > 1.0 ? std::sqrt(1.0 - 1.0 / (m_eta * m_eta)) : 0.0;
    const QuadratureRule g = gaussLegendre(64).mappedTo(0.0, 1.0);
    double sum = 0.0;
    for (size_t i = 0; i < g.x.size(); ++i) {
        const double v = g.x[i], mu = muC + (1.0 - muC) * v * v;
        sum += g.w[i] * 2.0 * (1.0 - muC) * v * (1.0 - fresnelDielectric(mu, 1.0 / m_eta)) * mu /
               (1.0 + mu);
    }
    return 0.5 * (m_sigmaS / m_sigmaT) * sum;
}

// ---------------------------------------------------------------------------------------------

const std::vector<std::string>& radialProfileNames() {
    static const std::vector<std::string> names = {
        "dipole", "better-dipole", "dirpole",       "dirpole-normalised",
        "burley", "photon-beam",   "photon-beam-ms"};
    return names;
}

NamedRadialProfile makeRadialProfile(const std::string& name, const ScalarMedium& m) {
    NamedRadialProfile out{name, nullptr, 0.0};
    if (name == "dipole" || name == "better-dipole") {
        const DipoleProfile p = DipoleProfile::make(parseModel(name), m);
        out.R = [p](double r) { return p.Rd(r); };
        out.total = p.totalReflectance();
    } else if (name == "dirpole" || name == "dirpole-normalised") {
        const double st = m.sigma_a + m.sigma_s;
        const double albedo = st > 0.0 ? m.sigma_s / st : 0.0;
        const DirectionalDipole d =
            name == "dirpole"
                ? DirectionalDipole(m.sigma_a, m.sigma_s, m.eta)
                : DirectionalDipole(m.sigma_a, m.sigma_s, m.eta, dirpoleEnergyScale(albedo, m.eta));
        out.R = [d](double r) { return d.radial(r); };
        out.total = d.isZero() ? 0.0 : integrateProfile(d);
    } else if (name == "burley") {
        const BurleyProfile b = BurleyProfile::searchlight(m.sigma_a, m.sigma_s, m.eta);
        out.R = [b](double r) { return b.R(r); };
        out.total = b.totalReflectance();
    } else if (name == "photon-beam" || name == "photon-beam-ms") {
        const PhotonBeamProfile b(m.sigma_a, m.sigma_s, m.eta);
        const bool multipleOnly = name == "photon-beam-ms";
        out.R = [b, multipleOnly](double r) { return multipleOnly ? b.multiple(r) : b.R(r); };
        out.total = multipleOnly ? b.multipleTotal() : b.totalReflectance();
    } else {
        std::string accepted;
        for (const std::string& n : radialProfileNames())
            accepted += (accepted.empty() ? "" : ", ") + n;
        LUCENT_THROW(ValueError, "unknown radial profile '", name, "' (accepted: ", accepted, ")");
    }
    return out;
}

}  // namespace lucent::dipole
