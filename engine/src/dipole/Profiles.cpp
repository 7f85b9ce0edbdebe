// SPDX-License-Identifier: MIT
/// @file
/// @brief Dipole, better-dipole and directional-dipole profiles (see Profiles.h for sources).

#include <lucent/core/Fresnel.h>
#include <lucent/dipole/HalfSpace.h>
#include <lucent/dipole/Profiles.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Quadrature.h>
#include <lucent/core/TableCache.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace lucent::dipole {
namespace {

constexpr double PI_D = 3.14159265358979323846;
constexpr double SIGMA_LIMIT = 1e6;  // mm⁻¹, the project's largest accepted coefficient

/// A Gauss–Legendre rule of N nodes (lucent/core/Quadrature.h) with ∫_a^b.
template <int N>
struct GaussLegendre {
    QuadratureRule rule = gaussLegendre(N);
    /// ∫_a^b f.
    template <typename F>
    double integrate(double a, double b, const F& f) const {
        const double h = 0.5 * (b - a), m = 0.5 * (a + b);
        double s = 0.0;
        for (int i = 0; i < N; ++i)
            s += rule.w[size_t(i)] * f(m + h * rule.x[size_t(i)]);
        return s * h;
    }
};

const GaussLegendre<64>& gl64() {
    static const GaussLegendre<64> g;
    return g;
}
const GaussLegendre<8>& gl8() {
    static const GaussLegendre<8> g;
    return g;
}

void checkMedium(double sigma_a, double sigma_s, double eta) {
    LUCENT_CHECK(std::isfinite(sigma_a) && sigma_a >= 0.0 && sigma_a <= SIGMA_LIMIT,
                 "dipole: sigma_a must be finite and in [0, 1e6] mm^-1 (got ", sigma_a, ")");
    LUCENT_CHECK(std::isfinite(sigma_s) && sigma_s >= 0.0 && sigma_s <= SIGMA_LIMIT,
                 "dipole: sigma_s' must be finite and in [0, 1e6] mm^-1 (got ", sigma_s, ")");
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0,
                 "dipole: eta must be in [1, 3] (got ", eta, ")");
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Fresnel

double fresnelDiffuseReflectanceJensen(double eta) {
    // Seed 004, Table 1 (Jensen et al. 2001, after Egan & Hilgeman).
    return -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
}

double fresnelMoment(int n, double eta) {
    LUCENT_CHECK(n >= 0 && n <= 2, "fresnelMoment: order must be 0, 1 or 2 (got ", n, ")");
    LUCENT_CHECK(std::isfinite(eta) && eta > 0.0, "fresnelMoment: eta must be > 0 (got ", eta, ")");
    // Light travels inside the medium (index η) towards the outside (index 1): relative index
    // n_t/n_i = 1/η. For η > 1, μ < μ_c = √(1 − 1/η²) is totally reflected (F = 1).
    const double rel = 1.0 / eta;
    const auto f = [&](double mu) { return fresnelDielectric(mu, rel) * std::pow(mu, n); };
    if (rel >= 1.0)
        return gl64().integrate(0.0, 1.0, f);
    const double muC = std::sqrt(1.0 - rel * rel);
    const double tir = std::pow(muC, n + 1) / (n + 1);
    // μ = μ_c + (1 − μ_c) t² removes the √(μ − μ_c) kink of F at the critical angle.
    const double rest = gl64().integrate(
        0.0, 1.0, [&](double t) { return f(muC + (1.0 - muC) * t * t) * 2.0 * (1.0 - muC) * t; });
    return tir + rest;
}

Model parseModel(const std::string& name) {
    if (name == "dipole")
        return Model::Dipole;
    if (name == "better-dipole")
        return Model::BetterDipole;
    if (name == "dirpole")
        return Model::Directional;
    LUCENT_THROW(ValueError, "unknown dipole model '", name,
                 "' (expected dipole, better-dipole or dirpole)");
}

const char* modelName(Model m) {
    switch (m) {
        case Model::Dipole:
            return "dipole";
        case Model::BetterDipole:
            return "better-dipole";
        case Model::Directional:
            return "dirpole";
    }
    return "?";
}

// ---------------------------------------------------------------------------------------------
// DipoleProfile

Boundary Boundary::of(double eta) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0,
                 "dipole: eta must be in [1, 3] (got ", eta, ")");
    return {eta, fresnelDiffuseReflectanceJensen(eta), fresnelMoment(1, eta),
            fresnelMoment(2, eta)};
}

DipoleProfile DipoleProfile::jensen(double sigma_a, double sigma_s, double eta) {
    checkMedium(sigma_a, sigma_s, eta);
    return make(Model::Dipole, sigma_a, sigma_s, Boundary::of(eta));
}

DipoleProfile DipoleProfile::better(double sigma_a, double sigma_s, double eta) {
    checkMedium(sigma_a, sigma_s, eta);
    return make(Model::BetterDipole, sigma_a, sigma_s, Boundary::of(eta));
}

DipoleProfile DipoleProfile::make(Model m, const ScalarMedium& medium) {
    LUCENT_CHECK(m != Model::Directional,
                 "DipoleProfile: the directional dipole is not radial; use DirectionalDipole");
    return m == Model::Dipole ? jensen(medium.sigma_a, medium.sigma_s, medium.eta)
                              : better(medium.sigma_a, medium.sigma_s, medium.eta);
}

DipoleProfile DipoleProfile::make(Model m, double sigma_a, double sigma_s, const Boundary& b) {
    LUCENT_CHECK(m != Model::Directional,
                 "DipoleProfile: the directional dipole is not radial; use DirectionalDipole");
    DipoleProfile p;
    p.m_model = m;
    const double sigmaTp = sigma_a + sigma_s;  // σt′ (Table 1)
    if (!(sigmaTp > 0.0))
        return p;                    // no medium: zero profile (documented clamp)
    p.m_alphaP = sigma_s / sigmaTp;  // α′ = σs′/σt′
    p.m_zr = 1.0 / sigmaTp;          // z_r = 1/σt′ (both models)
    if (m == Model::Dipole) {
        // Seed 004 Table 1: D = 1/(3σt′), σ = √(3σaσt′), A = (1+F_dr)/(1−F_dr), z_v = z_r + 4AD.
        p.m_D = 1.0 / (3.0 * sigmaTp);
        p.m_sigmaTr = std::sqrt(3.0 * sigma_a * sigmaTp);
        p.m_A = (1.0 + b.fdr) / (1.0 - b.fdr);
        p.m_cPhi = 0.0;
        p.m_cE = 1.0;
    } else {
        // d'Eon 2012: Grosjean's D = (2σa + σs′)/(3σt′²), σ_tr = √(σa/D); boundary condition from
        // the first two Fresnel moments, A = (1 + 3C₂)/(1 − 2C₁) (extrapolation distance
        // z_b = 2AD); exitance = C_φ φ + C_E E·n with C_φ = (1−2C₁)/4, C_E = (1−3C₂)/2.
        p.m_D = (2.0 * sigma_a + sigma_s) / (3.0 * sigmaTp * sigmaTp);
        p.m_sigmaTr = std::sqrt(sigma_a / p.m_D);
        p.m_A = (1.0 + 3.0 * b.c2) / (1.0 - 2.0 * b.c1);
        p.m_cPhi = 0.25 * (1.0 - 2.0 * b.c1);
        p.m_cE = 0.5 * (1.0 - 3.0 * b.c2);
    }
    p.m_zv = p.m_zr + 4.0 * p.m_A * p.m_D;  // virtual source height z_r + 2z_b
    return p;
}

double DipoleProfile::Rd(double r) const {
    if (isZero())
        return 0.0;
    r = std::abs(r);
    // Beyond 1e100 mm every term has underflowed (d³ overflows); avoids ∞·0.
    if (!(r < 1e100))
        return 0.0;
    const double r2 = r * r;
    const double dr = std::sqrt(r2 + m_zr * m_zr), dv = std::sqrt(r2 + m_zv * m_zv);
    const double s = m_sigmaTr;
    const double er = std::exp(-s * dr), ev = std::exp(-s * dv);
    // Flux term, Mertens et al. 2005 Table 1 (z_v enters with + because the virtual source is
    // negative and sits above the surface). (1 + σd)e^{−σd} is written as e^{−σd} + σd·e^{−σd} so
    // that σd → ∞ gives 0, not ∞·0.
    const auto decay = [](double x, double e) { return e > 0.0 ? e + x * e : 0.0; };
    const double flux =
        m_zr * decay(s * dr, er) / (dr * dr * dr) + m_zv * decay(s * dv, ev) / (dv * dv * dv);
    double value = m_cE * m_alphaP / (4.0 * PI_D) * flux;
    if (m_cPhi != 0.0) {
        // Fluence term of the better dipole (d'Eon 2012): α′/(4πD)(e^{−σd_r}/d_r − e^{−σd_v}/d_v).
        value += m_cPhi * m_alphaP / (4.0 * PI_D * m_D) * (er / dr - ev / dv);
    }
    return value;
}

double DipoleProfile::totalReflectance() const {
    if (isZero())
        return 0.0;
    const double s = m_sigmaTr;
    const double er = std::exp(-s * m_zr), ev = std::exp(-s * m_zv);
    // Seed 004 Eq. 7: ∫ z(1+σd)e^{−σd}/d³ 2πr dr = 2π e^{−σz} per source → ρ = α′/2 (e_r + e_v).
    double rho = 0.5 * m_alphaP * m_cE * (er + ev);
    if (m_cPhi != 0.0) {
        // ∫ e^{−σd}/d 2πr dr = 2π e^{−σz}/σ; the difference, written with expm1 so σ → 0 is exact.
        const double dz = m_zv - m_zr;
        const double diff = s > 0.0 ? -er * std::expm1(-s * dz) / s : dz;
        rho += 0.5 * m_alphaP * m_cPhi / m_D * diff;
    }
    return rho;
}

double DipoleProfile::reflectanceBeyond(double R) const {
    if (isZero())
        return 0.0;
    R = std::abs(R);
    if (!(R < 1e100))
        return 0.0;
    const double s = m_sigmaTr;
    const double dr = std::sqrt(R * R + m_zr * m_zr), dv = std::sqrt(R * R + m_zv * m_zv);
    const double er = std::exp(-s * dr), ev = std::exp(-s * dv);
    double tail = 0.5 * m_alphaP * m_cE * (m_zr * er / dr + m_zv * ev / dv);
    if (m_cPhi != 0.0) {
        // (e^{−σd_r} − e^{−σd_v})/σ with expm1, exact as σ → 0 (then d_v − d_r).
        const double dd = dv - dr;
        const double diff = s > 0.0 ? -er * std::expm1(-s * dd) / s : dd;
        tail += 0.5 * m_alphaP * m_cPhi / m_D * diff;
    }
    return tail;
}

// ---------------------------------------------------------------------------------------------
// DirectionalDipole

DirectionalDipole::DirectionalDipole(double sigma_a, double sigma_s, double eta, double energyScale)
    : DirectionalDipole(sigma_a, sigma_s, eta) {
    LUCENT_CHECK(std::isfinite(energyScale) && energyScale >= 0.0,
                 "DirectionalDipole: energy scale must be finite and >= 0 (got ", energyScale, ")");
    m_energyScale = energyScale;
    m_norm *= energyScale;
}

DirectionalDipole::DirectionalDipole(double sigma_a, double sigma_s, double eta) {
    checkMedium(sigma_a, sigma_s, eta);
    const double sigmaTp = sigma_a + sigma_s;
    if (sigmaTp <= 0.0 || sigma_s <= 0.0)
        return;  // zero profile (documented clamp)
    m_zero = false;
    m_sigmaTp = sigmaTp;
    const double alphaP = sigma_s / sigmaTp;
    m_alphaP = alphaP;
    // Frisvad et al. 2014, Sec. 4: D = (2σa + σs′)/(3σt′²), σ_tr = √(σa/D). (The authors'
    // reference program uses D = 1/(3σt′); identical at σa = 0, ρ lower by ≈ 3 % at α′ = 0.9.)
    // No α′ factor anywhere in S_d, as published: the model's total exceeds 1 at σa = 0
    // (docs/methods/dipole.md, "Why the directional dipole is too bright").
    m_D = (2.0 * sigma_a + sigma_s) / (3.0 * sigmaTp * sigmaTp);
    m_sigmaTr = std::sqrt(sigma_a / m_D);
    // C_φ(η) = (1 − 2C₁(η))/4, C_E(η) = (1 − 3C₂(η))/2, A = (1 − C_E(η))/(2C_φ(η)).
    m_cPhi = 0.25 * (1.0 - 2.0 * fresnelMoment(1, eta));
    m_cE = 0.5 * (1.0 - 3.0 * fresnelMoment(2, eta));
    m_A = (1.0 - m_cE) / (2.0 * m_cPhi);
    // External moments: C_φ(1/η) from light arriving from outside (relative index 1/η).
    m_cPhiInvEta = 0.25 * (1.0 - 2.0 * fresnelMoment(1, 1.0 / eta));
    // Extrapolation distance of the modified tangent plane: d_e = 2.131 D/√α′ (paper Eq. 21).
    m_de = 2.131 * m_D / std::sqrt(alphaP);
    // Exitance → radiance factor 1/(4C_φ(1/η)) and the 1/(4π²) of S′_d.
    m_norm = 1.0 / (4.0 * m_cPhiInvEta) / (4.0 * PI_D * PI_D);
}

double DirectionalDipole::sdPrime(const glm::dvec3& x, const glm::dvec3& w, double r,
                                  const glm::dvec3& no) const {
    // Frisvad et al. 2014, S′_d(x, ω, r): ray-source diffusion term.
    const double s = m_sigmaTr * r;
    if (s > 700.0)
        return 0.0;  // e^{−s} underflows double
    const double r2 = r * r;
    const double xw = glm::dot(x, w), wn = glm::dot(w, no), xn = glm::dot(x, no);
    const double fluence = m_cPhi * (r2 / m_D + 3.0 * (1.0 + s) * xw);
    const double flux = m_cE * (3.0 * m_D * (1.0 + s) * wn -
                                ((1.0 + s) + 3.0 * m_D * (3.0 * (1.0 + s) + s * s) / r2 * xw) * xn);
    return m_norm * std::exp(-s) / (r2 * r) * (fluence - flux);
}

double DirectionalDipole::Sd(const glm::dvec3& xi, const glm::dvec3& ni, const glm::dvec3& w12,
                             const glm::dvec3& xo, const glm::dvec3& no) const {
    if (m_zero)
        return 0.0;
    const glm::dvec3 x = xo - xi;
    const double r2 = glm::dot(x, x);
    if (!(r2 < 1e200))
        return 0.0;  // far beyond any diffusion length: underflowed
    // Modified tangent plane normal n_i* = x × (n_i × x)/|·| (n_i when x_o = x_i or x ∥ n_i).
    glm::dvec3 niStar = glm::cross(x, glm::cross(ni, x));
    const double len = glm::length(niStar);
    niStar = len > 1e-12 * std::max(r2, 1e-300) ? niStar / len : ni;
    // Virtual source mirrored in the extrapolated plane: x_v = x_i + 2A d_e n_i*,
    // ω_v = ω₁₂ − 2(ω₁₂·n_i*) n_i*.
    const glm::dvec3 xv = xi + 2.0 * m_A * m_de * niStar;
    const glm::dvec3 wv = w12 - 2.0 * glm::dot(w12, niStar) * niStar;
    const double dv = glm::length(xo - xv);
    // Distance to the real source, corrected near the point of incidence:
    // d_r² = r² + Dμ₀(Dμ₀ − 2d_e cos β) when μ₀ = −n_o·ω₁₂ > 0, else r² + (1/(3σt))².
    const double mu0 = -glm::dot(no, w12);
    double dr2;
    if (mu0 > 0.0) {
        const double xw = glm::dot(x, w12);
        const double cosBeta = -std::sqrt(std::max(0.0, r2 - xw * xw) / (r2 + m_de * m_de));
        dr2 = r2 + m_D * mu0 * (m_D * mu0 - 2.0 * m_de * cosBeta);
    } else {
        // The paper's 1/(3σt) uses the unreduced σt; Lucent's media are reduced (g = 0), so
        // σt = σt′ here.
        const double l = 1.0 / (3.0 * m_sigmaTp);
        dr2 = r2 + l * l;
    }
    const double dr = std::sqrt(dr2);
    const double value = sdPrime(x, w12, dr, no) - sdPrime(xo - xv, wv, dv, no);
    // The dipole difference can dip below zero in extreme geometry; radiance cannot: clamp
    // (paper §6.1).
    return std::isfinite(value) ? std::max(0.0, value) : 0.0;
}

double DirectionalDipole::radial(double r) const {
    if (m_zero)
        return 0.0;
    const glm::dvec3 n(0.0, 0.0, 1.0);
    return Sd(glm::dvec3(0.0), n, -n, glm::dvec3(std::abs(r), 0.0, 0.0), n) * 4.0 * PI_D *
           m_cPhiInvEta;
}

// ---------------------------------------------------------------------------------------------
// Quadrature and per-model helpers

double integrateRadial(double (*f)(const void*, double), const void* ctx, double scale) {
    LUCENT_CHECK(std::isfinite(scale) && scale > 0.0, "integrateRadial: scale must be > 0");
    const double lo = std::log(1e-9 * scale), hi = std::log(1e4 * scale);
    const int panels = 480;  // 0.064 e-folds per 8-point panel
    const double h = (hi - lo) / panels;
    double sum = 0.0;
    for (int i = 0; i < panels; ++i) {
        const double a = lo + i * h;
        sum += gl8().integrate(a, a + h, [&](double s) {
            const double r = std::exp(s);
            return f(ctx, r) * 2.0 * PI_D * r * r;  // dr = r ds
        });
    }
    // Tail r > R by t = 1/r: ∫_R^∞ f(r) 2πr dr = ∫_0^{1/R} f(1/t) 2π/t³ dt.
    const double tMax = 1.0 / std::exp(hi);
    const int tailPanels = 32;
    for (int i = 0; i < tailPanels; ++i) {
        const double a = tMax * i / tailPanels, b = tMax * (i + 1) / tailPanels;
        sum += gl8().integrate(
            a, b, [&](double t) { return f(ctx, 1.0 / t) * 2.0 * PI_D / (t * t * t); });
    }
    // Core r < 1e-9·scale, ≈ f(rMin)π rMin² (the dipoles' f is bounded there; Burley's and
    // photon beam diffusion's grow like 1/r, whose core is twice that — 10⁻¹⁸ of the total
    // either way; f(0) would be +∞ for them).
    const double rMin = std::exp(lo);
    sum += f(ctx, rMin) * PI_D * rMin * rMin;
    return sum;
}

double integrateProfile(const DipoleProfile& p) {
    if (p.isZero())
        return 0.0;
    return integrateRadial(
        [](const void* c, double r) { return static_cast<const DipoleProfile*>(c)->Rd(r); }, &p,
        p.zr());
}

double integrateProfile(const DirectionalDipole& p) {
    if (p.isZero())
        return 0.0;
    return integrateRadial(
        [](const void* c, double r) { return static_cast<const DirectionalDipole*>(c)->radial(r); },
        &p, p.D());
}

EnergyTarget parseEnergyTarget(const std::string& name) {
    if (name == "exact")
        return EnergyTarget::ExactHalfSpace;
    if (name == "better-dipole")
        return EnergyTarget::BetterDipole;
    throw ValueError("unknown energy target '" + name + "' (use exact or better-dipole)");
}

const char* energyTargetName(EnergyTarget t) {
    return t == EnergyTarget::ExactHalfSpace ? "exact" : "better-dipole";
}

double dirpoleEnergyScale(double alphaPrime, double eta, EnergyTarget target) {
    LUCENT_CHECK(std::isfinite(alphaPrime) && alphaPrime >= 0.0 && alphaPrime <= 1.0,
                 "dirpoleEnergyScale: alpha' must be in [0, 1] (got ", alphaPrime, ")");
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0,
                 "dirpoleEnergyScale: eta must be in [1, 3] (got ", eta, ")");
    // σt′ = 1 mm⁻¹: both totals are dimensionless functions of α′ and η only.
    const double a = std::max(alphaPrime, DIRPOLE_MIN_ALPHA);
    const ScalarMedium med{1.0 - a, a, eta};
    // ρ_dirpole: quadrature of the normal-incidence profile R(r) = S_d·4πC_φ(1/η) (Frisvad et
    // al. 2014); ρ_target: the exact half-space (adding–doubling) or d'Eon 2012's closed form
    // (§1 of docs/methods/dipole.md).
    const double wanted = target == EnergyTarget::ExactHalfSpace
                              ? halfSpaceReflectance(a, eta)
                              : DipoleProfile::make(Model::BetterDipole, med).totalReflectance();
    const double dirpole = integrateProfile(DirectionalDipole(med.sigma_a, med.sigma_s, eta));
    LUCENT_ASSERT(wanted > 0.0 && dirpole > 0.0);
    return wanted / dirpole;
}

namespace {
// DirpoleEnergyTable nodes: α′ ∈ [½, 1] uniform in s = √(1 − α′) (the totals are smooth in s,
// e^{−√(3(1−α′))} terms), α′ ∈ [DIRPOLE_MIN_ALPHA, ½] uniform in log α′ (the scale falls
// like α′ there); the table stores log s(α′), interpolated linearly in each variable.
constexpr int LOW_NODES = DirpoleEnergyTable::LOW_ALBEDO_NODES;
double tableAlpha(int i) {
    if (i < LOW_NODES) {  // low albedos, log-spaced
        const double t = double(i) / LOW_NODES;
        return std::exp(std::log(DIRPOLE_MIN_ALPHA) * (1.0 - t) + std::log(0.5) * t);
    }
    const double s = std::sqrt(0.5) *
                     (1.0 - double(i - LOW_NODES) / (DirpoleEnergyTable::NODES - 1 - LOW_NODES));
    return 1.0 - s * s;
}
}  // namespace

DirpoleEnergyTable::DirpoleEnergyTable(double eta, EnergyTarget target)
    : m_eta(eta), m_target(target) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0,
                 "DirpoleEnergyTable: eta must be in [1, 3] (got ", eta, ")");
    m_scale.resize(NODES);
    for (int i = 0; i < NODES; ++i)
        m_scale[size_t(i)] =
            std::log(dirpoleEnergyScale(std::clamp(tableAlpha(i), 0.0, 1.0), eta, target));
}

double DirpoleEnergyTable::scale(double alphaPrime) const {
    if (m_scale.empty())
        return 1.0;
    const double a = std::clamp(alphaPrime, DIRPOLE_MIN_ALPHA, 1.0);
    double x;  // continuous node index
    if (a < 0.5) {
        x = (std::log(a) - std::log(DIRPOLE_MIN_ALPHA)) /
            (std::log(0.5) - std::log(DIRPOLE_MIN_ALPHA)) * LOW_NODES;
    } else {
        const double s = std::sqrt(1.0 - a);
        x = LOW_NODES + (1.0 - s / std::sqrt(0.5)) * (NODES - 1 - LOW_NODES);
    }
    const int i = std::clamp(int(x), 0, NODES - 2);
    const double t = std::clamp(x - i, 0.0, 1.0);
    return std::exp((1.0 - t) * m_scale[size_t(i)] + t * m_scale[size_t(i) + 1]);
}

namespace {
/// Bilinear lookup in a row-major [albedo node][cosine node] table: albedo nodes uniform in
/// s = √(1 − α′) over [0, 1], cosine nodes uniform in `cosine01` ∈ [0, 1] (the tables of
/// DirpoleExitTable and DirpoleIncidenceTable; their GLSL twins are in the dirpole shaders).
double lookupAlbedoCosine(const std::vector<float>& values, int albedoNodes, int cosineNodes,
                          double alphaPrime, double cosine01) {
    const double s = std::sqrt(std::clamp(1.0 - alphaPrime, 0.0, 1.0)) * (albedoNodes - 1);
    const int i = std::min(int(s), albedoNodes - 2);
    const double fs = s - i;
    const double u = cosine01 * (cosineNodes - 1);
    const int j = std::min(int(u), cosineNodes - 2);
    const double fu = u - j;
    const auto at = [&](int a, int b) {
        return double(values[size_t(a) * size_t(cosineNodes) + size_t(b)]);
    };
    return (1.0 - fs) * ((1.0 - fu) * at(i, j) + fu * at(i, j + 1)) +
           fs * ((1.0 - fu) * at(i + 1, j) + fu * at(i + 1, j + 1));
}
}  // namespace

double DirpoleExitTable::albedoNode(int i) {
    const double s = double(i) / (ALBEDO_NODES - 1);
    return 1.0 - s * s;
}

DirpoleExitTable::DirpoleExitTable(double eta) : m_eta(eta) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0,
                 "DirpoleExitTable: eta must be in [1, 3] (got ", eta, ")");
    std::vector<double> cosines(COSINE_NODES);
    for (int j = 0; j < COSINE_NODES; ++j)
        cosines[size_t(j)] = cosineNode(j);
    // L_model(t) = T₂₁(t) ρ / (π(1 − 2C₁(1/η))), with the same ρ (the exact one) as L_exact.
    const double diffuseToRadiance = 1.0 / (PI_D * (1.0 - 2.0 * fresnelMoment(1, 1.0 / eta)));
    m_values.resize(size_t(ALBEDO_NODES) * COSINE_NODES);
    for (int i = 0; i < ALBEDO_NODES; ++i) {
        const double a = std::max(albedoNode(i), DIRPOLE_MIN_ALPHA);
        const HalfSpaceExitance exact = halfSpaceExitance(a, eta, 1.0, cosines);
        for (int j = 0; j < COSINE_NODES; ++j) {
            const double t = cosines[size_t(j)];
            const double model =
                (1.0 - fresnelDielectric(t, eta)) * exact.reflectance * diffuseToRadiance;
            LUCENT_ASSERT(model > 0.0);
            m_values[size_t(i) * COSINE_NODES + size_t(j)] =
                float(exact.radiance[size_t(j)] / model);
        }
    }
}

double DirpoleExitTable::correction(double alphaPrime, double cosOut) const {
    if (m_values.empty())
        return 1.0;
    return lookupAlbedoCosine(m_values, ALBEDO_NODES, COSINE_NODES, alphaPrime,
                              std::clamp(cosOut, 0.0, 1.0));
}

std::shared_ptr<const DirpoleEnergyTable> DirpoleEnergyTable::shared(double eta,
                                                                     EnergyTarget target) {
    return sharedTable<DirpoleEnergyTable>(std::make_pair(eta, int(target)),
                                           [&] { return DirpoleEnergyTable(eta, target); });
}

std::shared_ptr<const DirpoleExitTable> DirpoleExitTable::shared(double eta) {
    return sharedTable<DirpoleExitTable>(eta, [&] { return DirpoleExitTable(eta); });
}

double integrateSdOverPlane(const DirectionalDipole& d, double mu0) {
    LUCENT_CHECK(std::isfinite(mu0) && mu0 > 0.0 && mu0 <= 1.0,
                 "integrateSdOverPlane: mu0 must be in (0, 1] (got ", mu0, ")");
    if (d.isZero())
        return 0.0;
    // x_i at the origin of the plane z = 0 (normal +z), ω₁₂ in the xz plane; S_d is symmetric
    // in y, so the azimuth runs over [0, π] twice. Log r over [1e-7, 1e4]·D (the profile's
    // core and its e^{−σ_tr r} tail; beyond, < 1e-12 of the total for the albedos tabulated).
    const glm::dvec3 origin(0.0), normal(0.0, 0.0, 1.0);
    const glm::dvec3 w12(std::sqrt(std::max(0.0, 1.0 - mu0 * mu0)), 0.0, -mu0);
    static const QuadratureRule azimuth = gaussLegendre(32).mappedTo(0.0, PI_D);
    const double lo = std::log(1e-7 * d.D()), hi = std::log(1e4 * d.D());
    const int panels = 160;
    const double h = (hi - lo) / panels;
    double sum = 0.0;
    for (int i = 0; i < panels; ++i) {
        const double a = lo + i * h;
        sum += gl8().integrate(a, a + h, [&](double s) {
            const double r = std::exp(s);
            double ring = 0.0;
            for (size_t j = 0; j < azimuth.x.size(); ++j) {
                const glm::dvec3 xo(r * std::cos(azimuth.x[j]), r * std::sin(azimuth.x[j]), 0.0);
                ring += azimuth.w[j] * d.Sd(origin, normal, w12, xo, normal);
            }
            return 2.0 * ring * r * r;  // dA = r dr dφ, dr = r ds
        });
    }
    return sum;
}

DirpoleIncidenceTable::DirpoleIncidenceTable(double eta) : m_eta(eta) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0,
                 "DirpoleIncidenceTable: eta must be in [1, 3] (got ", eta, ")");
    m_minCosine = std::max(eta > 1.0 ? std::sqrt(1.0 - 1.0 / (eta * eta)) : 0.0, 0.05);
    m_values.assign(size_t(ALBEDO_NODES) * COSINE_NODES, 1.f);
    parallelFor(0, ALBEDO_NODES, [&](int64_t i0, int64_t i1) {
        for (int64_t i = i0; i < i1; ++i) {
            const double s = double(i) / (ALBEDO_NODES - 1);
            const double a = std::max(1.0 - s * s, DIRPOLE_MIN_ALPHA);
            const DirectionalDipole d(1.0 - a, a, eta);  // σt′ = 1 mm⁻¹
            const double modelNormal = integrateSdOverPlane(d, 1.0);
            const double exactNormal = halfSpaceReflectance(a, eta, 1.0);
            for (int j = 0; j + 1 < COSINE_NODES; ++j) {  // the last node is μ₀ = 1: k = 1
                const double mu0 = m_minCosine + (1.0 - m_minCosine) * j / (COSINE_NODES - 1);
                const double k = (halfSpaceReflectance(a, eta, mu0) / exactNormal) /
                                 (integrateSdOverPlane(d, mu0) / modelNormal);
                m_values[size_t(i) * COSINE_NODES + size_t(j)] = float(k);
            }
        }
    });
}

std::shared_ptr<const DirpoleIncidenceTable> DirpoleIncidenceTable::shared(double eta) {
    return sharedTable<DirpoleIncidenceTable>(eta, [&] { return DirpoleIncidenceTable(eta); });
}

double DirpoleIncidenceTable::correction(double alphaPrime, double mu0) const {
    if (m_values.empty())
        return 1.0;
    return lookupAlbedoCosine(m_values, ALBEDO_NODES, COSINE_NODES, alphaPrime,
                              std::clamp((mu0 - m_minCosine) / (1.0 - m_minCosine), 0.0, 1.0));
}

double totalReflectance(Model m, const ScalarMedium& medium) {
    if (m == Model::Directional)
        return integrateProfile(DirectionalDipole(medium.sigma_a, medium.sigma_s, medium.eta));
    return DipoleProfile::make(m, medium).totalReflectance();
}

double radialProfile(Model m, const ScalarMedium& medium, double r) {
    if (m == Model::Directional)
        return DirectionalDipole(medium.sigma_a, medium.sigma_s, medium.eta).radial(r);
    return DipoleProfile::make(m, medium).Rd(r);
}

}  // namespace lucent::dipole
