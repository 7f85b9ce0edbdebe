// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/core/Quadrature.h>
#include <lucent/dipole/HalfSpace.h>
#include <lucent/dipole/Profiles.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

using namespace lucent;
using namespace lucent::dipole;

namespace {
// Jensen et al. 2001 Table 2 values (mm⁻¹), one channel each, plus extremes.
struct Case {
    double sigma_a, sigma_s, eta;
};
const std::vector<Case> CASES = {
    {0.0021, 2.19, 1.3},  // marble (red)
    {0.0041, 2.62, 1.3},  // marble (green)
    {0.032, 0.74, 1.3},   // skin1 (red)
    {0.0014, 0.70, 1.3},  // ketchup-ish, low absorption
    {0.5, 0.5, 1.0},      // α′ = 0.5, matched boundary
    {1.0, 0.01, 2.5},     // strongly absorbing, high index
    {0.0, 1.0, 1.3},      // σa = 0: no absorption
    {1e-6, 1e6, 1.5},     // tiny mean free path
    {1e-6, 1e-6, 1.3},    // huge mean free path
};
}  // namespace

TEST(Fresnel, MomentsMatchKnownValues) {
    // η = 1: no boundary, no reflection.
    EXPECT_NEAR(fresnelMoment(1, 1.0), 0.0, 1e-12);
    // Normal incidence reflectance ((η−1)/(η+1))² for η = 1.5 is 0.04.
    EXPECT_NEAR(fresnelDielectric(1.0, 1.5), 0.04, 1e-12);
    EXPECT_DOUBLE_EQ(fresnelDielectric(0.1, 1.0 / 1.5), 1.0);  // beyond critical angle
    // 2C₁ is the internal diffuse reflectance that Jensen's F_dr fits (Egan–Hilgeman fit,
    // quoted accurate to about 1%): agreement within 0.01 over the fitted range.
    for (double eta = 1.1; eta <= 2.0; eta += 0.1)
        EXPECT_NEAR(2.0 * fresnelMoment(1, eta), fresnelDiffuseReflectanceJensen(eta), 0.012)
            << "eta " << eta;
    // C₀ ≥ C₁ ≥ C₂ (μⁿ ≤ 1) and all in [0, 1].
    for (double eta : {0.5, 0.8, 1.3, 2.5}) {
        const double c0 = fresnelMoment(0, eta), c1 = fresnelMoment(1, eta),
                     c2 = fresnelMoment(2, eta);
        EXPECT_GE(c0, c1);
        EXPECT_GE(c1, c2);
        EXPECT_GE(c2, 0.0);
        EXPECT_LE(c0, 1.0);
    }
}

TEST(Fresnel, MomentQuadratureIsConverged) {
    // Internal reflection at η = 1.3: C₁ = μ_c²/2 + ∫_{μc}^1 F μ dμ; compare the split Gauss
    // rule with a fine midpoint rule (error O(h^1.5) ≈ 1e-7 at 2e5 cells).
    const double eta = 1.3, rel = 1.0 / eta;
    const int n = 200000;
    double s = 0.0;
    for (int i = 0; i < n; ++i) {
        const double mu = (i + 0.5) / n;
        s += fresnelDielectric(mu, rel) * mu / n;
    }
    EXPECT_NEAR(fresnelMoment(1, eta), s, 1e-6);
}

TEST(Profiles, JensenMatchesTable1ByHand) {
    // Seed 004 Table 1 evaluated by hand for σa = 0.0021, σs′ = 2.19, η = 1.3 at r = 1 mm.
    const double sa = 0.0021, ss = 2.19, eta = 1.3;
    const double st = sa + ss, ap = ss / st, D = 1 / (3 * st), sig = std::sqrt(3 * sa * st);
    const double fdr = -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
    const double A = (1 + fdr) / (1 - fdr), zr = 1 / st, zv = zr + 4 * A * D;
    const double r = 1.0, dr = std::sqrt(r * r + zr * zr), dv = std::sqrt(r * r + zv * zv);
    const double expected = ap / (4 * M_PI) *
                            (zr * (1 + sig * dr) * std::exp(-sig * dr) / (dr * dr * dr) +
                             zv * (1 + sig * dv) * std::exp(-sig * dv) / (dv * dv * dv));
    const DipoleProfile p = DipoleProfile::jensen(sa, ss, eta);
    EXPECT_NEAR(p.Rd(r), expected, 1e-14 * expected);
    // Jensen's closed form R_d = (α′/2)(1 + e^{−(4/3)A√(3(1−α′))}) e^{−√(3(1−α′))}.
    const double s3 = std::sqrt(3 * (1 - ap));
    const double closed = 0.5 * ap * (1 + std::exp(-4.0 / 3.0 * A * s3)) * std::exp(-s3);
    EXPECT_NEAR(p.totalReflectance(), closed, 1e-12);
}

TEST(Profiles, NumericalIntegralAgreesWithClosedForm) {
    for (const Case& c : CASES) {
        for (Model m : {Model::Dipole, Model::BetterDipole}) {
            const DipoleProfile p = DipoleProfile::make(m, {c.sigma_a, c.sigma_s, c.eta});
            const double closed = p.totalReflectance(), numeric = integrateProfile(p);
            // Required agreement 1e-4 relative (task); the quadrature reaches ~1e-9.
            EXPECT_NEAR(numeric, closed, 1e-4 * closed)
                << modelName(m) << " sa " << c.sigma_a << " ss " << c.sigma_s;
            EXPECT_GT(closed, 0.0);
            EXPECT_LE(closed, 1.0 + 1e-12);
        }
    }
}

TEST(Profiles, EnergyConservedWithoutAbsorption) {
    // σa = 0: every photon leaves again; both dipoles integrate to exactly 1 (α′ = 1).
    for (double eta : {1.0, 1.3, 2.5}) {
        EXPECT_NEAR(DipoleProfile::jensen(0.0, 1.0, eta).totalReflectance(), 1.0, 1e-12);
        EXPECT_NEAR(DipoleProfile::better(0.0, 1.0, eta).totalReflectance(), 1.0, 1e-12);
    }
}

TEST(Profiles, ScaleInvariance) {
    // R_d scales as k² under σ → kσ, r → r/k (dimensional analysis): ρ is unchanged.
    const DipoleProfile a = DipoleProfile::better(0.01, 1.0, 1.4);
    const DipoleProfile b = DipoleProfile::better(0.1, 10.0, 1.4);
    EXPECT_NEAR(a.totalReflectance(), b.totalReflectance(), 1e-12);
    EXPECT_NEAR(b.Rd(0.05), 100.0 * a.Rd(0.5), 1e-10 * b.Rd(0.05));
}

TEST(Profiles, DirectionalDipoleIsSymmetricAtNormalIncidenceAndFinite) {
    const DirectionalDipole d(0.0021, 2.19, 1.3);
    const glm::dvec3 n(0, 0, 1);
    // Rotational symmetry at normal incidence.
    for (double r : {0.01, 0.3, 2.0}) {
        const double a = d.Sd({0, 0, 0}, n, -n, {r, 0, 0}, n);
        const double b = d.Sd({0, 0, 0}, n, -n, {0, r, 0}, n);
        const double c = d.Sd({0, 0, 0}, n, -n, {r / std::sqrt(2.0), r / std::sqrt(2.0), 0}, n);
        EXPECT_NEAR(a, b, 1e-12 * a);
        EXPECT_NEAR(a, c, 1e-9 * a);
        EXPECT_GT(a, 0.0);
    }
    // Oblique incidence: more light exits on the far side of the refracted ray (forward).
    const glm::dvec3 w12 = glm::normalize(glm::dvec3(0.5, 0, -1));
    EXPECT_GT(d.Sd({0, 0, 0}, n, w12, {1, 0, 0}, n), d.Sd({0, 0, 0}, n, w12, {-1, 0, 0}, n));
    // Total diffuse reflectance (quadrature) is positive and falls monotonically as σa grows
    // (more absorption, less exitance). The model is not normalised to ≤ 1 (docs/methods/
    // dipole.md, "Directional dipole"), so no upper bound is asserted here.
    double previous = INFINITY;
    for (double sa : {0.0, 1e-3, 1e-2, 0.1, 1.0, 10.0}) {
        const double rho = integrateProfile(DirectionalDipole(sa, 1.0, 1.3));
        EXPECT_GT(rho, 0.0);
        EXPECT_LT(rho, previous) << "sa " << sa;
        previous = rho;
    }
}

TEST(Profiles, DirectionalTotalMatchesTermByTermDerivationOfThePublishedModel) {
    // Frisvad et al. 2014 at σa = 0 (σ_tr = 0), normal incidence on a plane, written out by hand
    // (docs/methods/dipole.md, "Why the directional dipole is too bright"): x = (r, 0, 0),
    // ω₁₂ = −n, n_i* = n, x_v = x_i + h n with h = 2A d_e, ω_v = +n. With the radial profile
    // R = S_d·4πC_φ(1/η) the prefactor is 1/(4π), and ∫ 2πr dr/(4π) = ½∫ r dr gives
    //   real:    C_φ/(D d_r) + 3D C_E/d_r³
    //   virtual: −[C_φ(d_v²/D − 3h) − C_E(3D + h − 9Dh²/d_v²)]/d_v³,
    // whose directional and flux parts integrate in closed form (∫r/d_v³ = 1/h,
    // ∫r/d_v⁵ = 1/(3h³)):  ρ = (3/2)C_φ + C_E/2 + (C_φ/2D)·I₁ + (3D C_E/2)·I₃,
    // I₁ = ∫ r(1/d_r − 1/d_v) dr, I₃ = ∫ r/d_r³ dr, d_r² = r² + D(D + 2d_e r/√(r² + d_e²)).
    // I₁, I₃ here use a midpoint rule in t = r/(r + D) (400 000 cells: error ≪ 1e-6), a
    // layout unrelated to integrateRadial; agreement to 1e-4 (the library quadrature's own
    // bound) shows the code integrates exactly the published S_d.
    for (double eta : {1.0, 1.3, 1.5}) {
        const DirectionalDipole d(0.0, 1.0, eta);
        const double D = d.D(), de = d.de();
        const double cPhi = 0.25 * (1.0 - 2.0 * fresnelMoment(1, eta));
        const double cE = 0.5 * (1.0 - 3.0 * fresnelMoment(2, eta));
        const double h = 2.0 * (1.0 - cE) / (2.0 * cPhi) * de;
        const int n = 400000;
        double i1 = 0.0, i3 = 0.0;
        for (int i = 0; i < n; ++i) {
            const double t = (i + 0.5) / n, r = D * t / (1 - t), drdt = D / ((1 - t) * (1 - t));
            const double dr =
                std::sqrt(r * r + D * (D + 2.0 * de * r / std::sqrt(r * r + de * de)));
            const double dv = std::sqrt(r * r + h * h);
            i1 += r * (1.0 / dr - 1.0 / dv) * drdt / n;
            i3 += r / (dr * dr * dr) * drdt / n;
        }
        const double expected = 1.5 * cPhi + 0.5 * cE + cPhi / (2.0 * D) * i1 + 1.5 * D * cE * i3;
        EXPECT_NEAR(integrateProfile(d), expected, 1e-4 * expected) << "eta " << eta;
    }
    // The published model itself exceeds the energy bound ρ ≤ 1 of a non-absorbing half-space:
    // at η = 1 the virtual source's directional term alone gives (3/2)C_φ = 0.375 and the total
    // is 1.3395 (1.3405 with the authors' polynomial Fresnel fits, whose residual at η = 1 makes
    // C_E = 0.5035). This pins that the implementation is the published model, not a bug in it.
    const double rho1 = integrateProfile(DirectionalDipole(0.0, 1.0, 1.0));
    EXPECT_NEAR(rho1, 1.3395, 2e-4);
    EXPECT_GT(rho1, 1.0);
}

TEST(Profiles, DirectionalMatchesTheAuthorsFormulationAtObliqueGeometry) {
    // S_d written the way the authors' reference program lays it out (Hachisuka & Frisvad,
    // dirpole.cpp; docs/methods/dipole.md §1): n_i* = x̂ × normalize(n_i × x), ω_v = reflection
    // of ω₁₂ in n_i*, front-lit d_r² = Dμ₀(Dμ₀ − 2d_e cos β) + r², back-lit r² + 1/(3σt)².
    // Different algebra from Profiles.cpp (there n_i* = x × (n_i × x)/|·|); D, σ_tr and d_e
    // are taken from the object (the program uses D = 1/(3σt′), we Grosjean's D). Oblique
    // incidence, tilted exit normal, exit point off the plane of incidence, front- and back-lit.
    const double sa = 0.05, ss = 1.2, eta = 1.3;
    const DirectionalDipole d(sa, ss, eta);
    const double D = d.D(), de = d.de(), str = d.sigmaTr(), st = sa + ss;
    const double cPhi = 0.25 * (1.0 - 2.0 * fresnelMoment(1, eta));
    const double cE = 0.5 * (1.0 - 3.0 * fresnelMoment(2, eta));
    const double norm = 1.0 / (1.0 - 2.0 * fresnelMoment(1, 1.0 / eta));
    const double A = (1.0 - cE) / (2.0 * cPhi);
    const auto spd = [&](glm::dvec3 x, glm::dvec3 w, double r, glm::dvec3 n) {
        const double s = str * r, xw = glm::dot(x, w);
        const double t0 = norm / (4.0 * M_PI * M_PI) * std::exp(-s) / (r * r * r);
        const double t1 = r * r / D + 3.0 * (1.0 + s) * xw;
        const double t2 = 3.0 * D * (1.0 + s) * glm::dot(w, n);
        const double t3 =
            ((1.0 + s) + 3.0 * D * (3.0 * (1.0 + s) + s * s) / (r * r) * xw) * glm::dot(x, n);
        return t0 * (cPhi * t1 - cE * (t2 - t3));
    };
    const glm::dvec3 xi(0.0), ni(0, 0, 1);
    const glm::dvec3 w12 = glm::normalize(glm::dvec3(0.4, 0.1, -1.0));
    struct Exit {
        glm::dvec3 xo, no;
    };
    const Exit exits[] = {
        {{0.7, 0.3, -0.05}, glm::normalize(glm::dvec3(0.1, -0.2, 1.0))},  // front-lit, near
        {{-1.5, 0.8, 0.2}, glm::normalize(glm::dvec3(-0.3, 0.1, 1.0))},   // front-lit, behind
        {{0.5, -0.2, -2.0}, glm::normalize(glm::dvec3(0.2, 0.1, -1.0))},  // back-lit (μ₀ < 0)
    };
    for (const Exit& e : exits) {
        const glm::dvec3 x = e.xo - xi;
        const double r = glm::length(x);
        const glm::dvec3 niS = glm::cross(x / r, glm::normalize(glm::cross(ni, x)));
        const glm::dvec3 wv = w12 - niS * (2.0 * glm::dot(w12, niS));
        const double cosBeta =
            -std::sqrt((r * r - glm::dot(x, w12) * glm::dot(x, w12)) / (r * r + de * de));
        const double mu0 = -glm::dot(e.no, w12);
        const double dr = mu0 > 0.0 ? std::sqrt(D * mu0 * (D * mu0 - 2.0 * de * cosBeta) + r * r)
                                    : std::sqrt(1.0 / (9.0 * st * st) + r * r);
        const glm::dvec3 xoxv = e.xo - (xi + niS * (2.0 * A * de));
        const double expected =
            std::max(0.0, spd(x, w12, dr, e.no) - spd(xoxv, wv, glm::length(xoxv), e.no));
        const double got = d.Sd(xi, ni, w12, e.xo, e.no);
        EXPECT_GT(expected, 0.0);
        EXPECT_NEAR(got, expected, 1e-12 * expected) << "xo " << e.xo.x << ", " << e.xo.y;
    }
}

TEST(Profiles, DirectionalQuadratureIsConverged) {
    // Two radial quadratures of different layout agree (log-panel rule vs a plain t = r/(r+s)
    // map): checks the numerical total the CLI prints for the directional dipole.
    const DirectionalDipole d(0.01, 1.0, 1.3);
    const double a = integrateProfile(d);
    const int n = 400000;
    const double s = d.D();
    double b = 0.0;
    for (int i = 0; i < n; ++i) {
        const double t = (i + 0.5) / n, r = s * t / (1 - t), drdt = s / ((1 - t) * (1 - t));
        b += d.radial(r) * 2 * M_PI * r * drdt / n;
    }
    EXPECT_NEAR(a, b, 1e-4 * a);
}

TEST(Profiles, StressFiniteAndNonNegative) {
    const std::vector<double> sigmas = {0.0, 1e-6, 1e-3, 1.0, 1e3, 1e6};
    const std::vector<double> radii = {0.0, 1e-9, 1e-3, 1.0, 1e3, 1e9, 1e300};
    for (double sa : sigmas)
        for (double ss : sigmas)
            for (double eta : {1.0, 1.3, 2.5}) {
                for (Model m : {Model::Dipole, Model::BetterDipole}) {
                    const DipoleProfile p = DipoleProfile::make(m, {sa, ss, eta});
                    const double rho = p.totalReflectance();
                    ASSERT_TRUE(std::isfinite(rho));
                    ASSERT_GE(rho, 0.0);
                    ASSERT_LE(rho, 1.0 + 1e-12);
                    for (double r : radii) {
                        const double v = p.Rd(r);
                        ASSERT_TRUE(std::isfinite(v)) << sa << " " << ss << " " << r;
                        ASSERT_GE(v, 0.0) << sa << " " << ss << " " << r;
                    }
                }
                const DirectionalDipole d(sa, ss, eta);
                for (double r : radii) {
                    const double v = d.radial(r);
                    ASSERT_TRUE(std::isfinite(v)) << sa << " " << ss << " " << r;
                    ASSERT_GE(v, 0.0);
                }
                // Grazing incidence and back-lit exit.
                const glm::dvec3 n(0, 0, 1);
                const glm::dvec3 graze = glm::normalize(glm::dvec3(1, 0, -1e-9));
                ASSERT_TRUE(std::isfinite(d.Sd({0, 0, 0}, n, graze, {0.5, 0, 0}, n)));
                ASSERT_TRUE(std::isfinite(d.Sd({0, 0, 0}, n, -n, {0, 0, -1}, -n)));
                ASSERT_GE(d.Sd({0, 0, 0}, n, -n, {0, 0, 0}, n), 0.0);
            }
}

TEST(Profiles, BadInputIsAClearError) {
    EXPECT_THROW(DipoleProfile::jensen(-1.0, 1.0, 1.3), ValueError);
    EXPECT_THROW(DipoleProfile::jensen(1.0, NAN, 1.3), ValueError);
    EXPECT_THROW(DipoleProfile::better(1.0, 1.0, 0.9), ValueError);
    EXPECT_THROW(DipoleProfile::better(1.0, 2e6, 1.3), ValueError);
    EXPECT_THROW(DirectionalDipole(1.0, 1.0, 3.5), ValueError);
    EXPECT_THROW(parseModel("tripole"), ValueError);
    EXPECT_EQ(parseModel("better-dipole"), Model::BetterDipole);
    // No medium / no scattering: zero profile (documented clamp).
    EXPECT_EQ(DipoleProfile::jensen(0.0, 0.0, 1.3).Rd(0.0), 0.0);
    EXPECT_EQ(DipoleProfile::better(1.0, 0.0, 1.3).totalReflectance(), 0.0);
}

// ---------------------------------------------------------------------------------------------
// Energy-normalised directional dipole (docs/methods/dipole.md §1)

TEST(DirpoleEnergy, NormalisedTotalEqualsItsTarget) {
    // The scale is computed at σt′ = 1 mm⁻¹; applied to media of other σt′ it must still give
    // the target's total (the exact half-space's or the better dipole's), since both totals
    // depend on α′ and η only. Tolerance 1e-4: the quadrature's agreement with closed forms
    // (§1, "Quadrature"); with the table, + 5e-4 interpolation.
    for (EnergyTarget target : {EnergyTarget::ExactHalfSpace, EnergyTarget::BetterDipole})
        for (double eta : {1.0, 1.3, 1.5, 2.5}) {
            const DirpoleEnergyTable table(eta, target);
            for (double a : {0.02, 0.3, 0.5, 0.8, 0.9, 0.99, 1.0}) {
                const double sigmaT = 7.3;  // mm⁻¹
                const double ss = a * sigmaT, sa = sigmaT - ss;
                const double wanted = target == EnergyTarget::ExactHalfSpace
                                          ? halfSpaceReflectance(a, eta)
                                          : totalReflectance(Model::BetterDipole, {sa, ss, eta});
                const double normalised = integrateProfile(
                    DirectionalDipole(sa, ss, eta, dirpoleEnergyScale(a, eta, target)));
                EXPECT_NEAR(normalised, wanted, 1e-4 * wanted)
                    << energyTargetName(target) << " alpha' " << a << " eta " << eta;
                const double tabulated =
                    integrateProfile(DirectionalDipole(sa, ss, eta, table.scale(a)));
                EXPECT_NEAR(tabulated, wanted, 6e-4 * wanted)
                    << energyTargetName(target) << " alpha' " << a << " eta " << eta;
            }
        }
    EXPECT_EQ(parseEnergyTarget("exact"), EnergyTarget::ExactHalfSpace);
    EXPECT_EQ(parseEnergyTarget("better-dipole"), EnergyTarget::BetterDipole);
    EXPECT_THROW(parseEnergyTarget("published"), ValueError);
}

TEST(DirpoleEnergy, TableMatchesExactScaleBetweenNodes) {
    // Dense sweep (between and on nodes, both segments of the table), for both targets.
    for (EnergyTarget target : {EnergyTarget::ExactHalfSpace, EnergyTarget::BetterDipole}) {
        double worst = 0.0;
        for (double eta : {1.0, 1.4, 2.5}) {
            const DirpoleEnergyTable table(eta, target);
            for (int i = 0; i <= 200; ++i) {
                const double a = i < 100 ? std::exp(std::log(1e-3) * (1.0 - (i + 0.37) / 100.0))
                                         : 1.0 - std::pow((200 - i + 0.37) / 100.0, 2) * 0.5;
                const double exact = dirpoleEnergyScale(std::clamp(a, 0.0, 1.0), eta, target);
                worst = std::max(worst, std::abs(table.scale(a) / exact - 1.0));
            }
        }
        std::printf("dirpole energy table (%s): worst interpolation error %.2e\n",
                    energyTargetName(target), worst);
        EXPECT_LT(worst, 5e-4);
    }
}

TEST(DirpoleExit, CorrectionMovesLightBetweenDirectionsNotTheTotal) {
    // c(α′, t) = L_exact(t) / L_model(t) with L_model(t) = T₂₁(t) ρ / (π(1 − 2C₁(1/η))), both
    // carrying the exact ρ: its flux-weighted mean 2∫ c(t) T₂₁(t) t dt / (1 − 2C₁(1/η)) is 1.
    // Through the table: its bilinear interpolation (16 cosines) and the solver's 3·10⁻⁵;
    // 2·10⁻³.
    const QuadratureRule g = gaussLegendre(64).mappedTo(0.0, 1.0);
    for (double eta : {1.0, 1.3, 2.0}) {
        const DirpoleExitTable table(eta);
        const double norm = 1.0 - 2.0 * fresnelMoment(1, 1.0 / eta);
        for (double a : {0.2, 0.68, 0.84, 0.96, 0.998, 1.0}) {
            double mean = 0.0;
            for (size_t k = 0; k < g.x.size(); ++k)
                mean += 2.0 * g.w[k] * g.x[k] * (1.0 - fresnelDielectric(g.x[k], eta)) *
                        table.correction(a, g.x[k]) / norm;
            EXPECT_NEAR(mean, 1.0, 2e-3) << "eta " << eta << " alpha' " << a;
        }
    }
}

TEST(DirpoleExit, TableMatchesTheSolverBetweenNodes) {
    // Between the nodes (both axes) the bilinear table against c from the solver directly.
    // Relative bounds from the curvature of c between 16 cosine nodes: 2·10⁻³ for t ≥ 0.2;
    // 1.5·10⁻² in the first two intervals (t < 0.13, grazing exit; at η = 1 H(μ) bends as
    // μ ln μ there: 9·10⁻³ at t = 0.03, 2.2·10⁻³ at 0.1; t < 0.2 is 4 % of a sphere's image).
    double worst = 0.0, worstGrazing = 0.0;
    for (double eta : {1.0, 1.3}) {
        const DirpoleExitTable table(eta);
        const double toRadiance = 1.0 / (M_PI * (1.0 - 2.0 * fresnelMoment(1, 1.0 / eta)));
        for (double a : {0.3, 0.678, 0.838, 0.9585, 0.998}) {
            const std::vector<double> cosines = {0.03, 0.1, 0.27, 0.5, 0.81, 0.99, 1.0};
            const HalfSpaceExitance e = halfSpaceExitance(a, eta, 1.0, cosines);
            for (size_t k = 0; k < cosines.size(); ++k) {
                const double model =
                    (1.0 - fresnelDielectric(cosines[k], eta)) * e.reflectance * toRadiance;
                const double exact = e.radiance[k] / model;
                double& w = cosines[k] < 0.2 ? worstGrazing : worst;
                w = std::max(w, std::abs(table.correction(a, cosines[k]) / exact - 1.0));
            }
        }
    }
    std::printf("dirpole exit table: worst interpolation error %.2e (t >= 0.2), %.2e (t < 0.2)\n",
                worst, worstGrazing);
    EXPECT_LT(worst, 2e-3);
    EXPECT_LT(worstGrazing, 1.5e-2);
    EXPECT_EQ(DirpoleExitTable().correction(0.5, 0.5), 1.0);  // empty: no correction
    EXPECT_THROW(DirpoleExitTable(0.5), ValueError);
}

TEST(DirpoleIncidence, PlaneIntegralAtNormalIncidenceIsTheRadialOne) {
    // ∫ S_d dA over the plane (log r × azimuth) times π(1 − 2C₁(1/η)) at μ₀ = 1 against the
    // radial quadrature of the same model: two quadratures of one integral, 10⁻⁴.
    for (double eta : {1.0, 1.3, 2.0})
        for (double a : {0.3, 0.84, 0.99}) {
            const DirectionalDipole d(1.0 - a, a, eta);
            const double plane =
                integrateSdOverPlane(d, 1.0) * M_PI * (1.0 - 2.0 * fresnelMoment(1, 1.0 / eta));
            const double radial = integrateProfile(d);
            EXPECT_NEAR(plane, radial, 1e-4 * radial) << "eta " << eta << " alpha' " << a;
        }
    EXPECT_THROW(integrateSdOverPlane(DirectionalDipole(0.1, 1.0, 1.3), 0.0), ValueError);
}

TEST(DirpoleIncidence, CorrectedTotalIsExactAtEveryIncidence) {
    // The energy scale (normal incidence) times k(α′, μ₀) makes the model's total at refracted
    // cosine μ₀ the exact half-space's. Off the nodes the bilinear table adds its error: 3·10⁻³
    // (k varies by ≤ 0.25 over the table, 8 cosines × 24 albedos), at σt′ = 2.5 mm⁻¹ to check
    // the scale invariance.
    double worst = 0.0;
    for (double eta : {1.0, 1.3}) {
        const DirpoleEnergyTable energy(eta);
        const DirpoleIncidenceTable incidence(eta);
        EXPECT_NEAR(incidence.correction(0.7, 1.0), 1.0, 1e-6);
        const double exitFactor = M_PI * (1.0 - 2.0 * fresnelMoment(1, 1.0 / eta));
        for (double a : {0.678, 0.838, 0.9585, 0.998})
            for (double mu0 : {0.97, 0.83, 0.7, 0.55, 0.3}) {
                if (mu0 < incidence.minCosine())
                    continue;
                const double sigmaT = 2.5;
                const DirectionalDipole d(sigmaT * (1.0 - a), sigmaT * a, eta,
                                          energy.scale(a) * incidence.correction(a, mu0));
                const double total = integrateSdOverPlane(d, mu0) * exitFactor;
                const double exact = halfSpaceReflectance(a, eta, mu0);
                worst = std::max(worst, std::abs(total / exact - 1.0));
                EXPECT_NEAR(total, exact, 3e-3 * exact)
                    << "eta " << eta << " alpha' " << a << " mu0 " << mu0;
            }
    }
    std::printf("dirpole incidence table: worst total error %.2e\n", worst);
    EXPECT_EQ(DirpoleIncidenceTable().correction(0.5, 0.5), 1.0);
}

TEST(DirpoleEnergy, ScaleIsFiniteForAllAlbedosAndIndices) {
    double lo = 1e30, hi = 0.0;
    for (double eta = 1.0; eta <= 2.5 + 1e-9; eta += 0.25)
        for (double a : {0.0, 1e-6, 1e-3, 0.01, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99, 0.999, 1.0}) {
            const double s = dirpoleEnergyScale(a, eta);
            ASSERT_TRUE(std::isfinite(s) && s > 0.0) << "alpha' " << a << " eta " << eta;
            lo = std::min(lo, s);
            hi = std::max(hi, s);
        }
    std::printf("dirpole energy scale over alpha' in [0,1], eta in [1,2.5]: [%.4f, %.4f]\n", lo,
                hi);
    // The published total at σa = 0, η = 1 is 1.3395 (§1); both targets are 1 there (no
    // absorption: all light returns), so the scale is its inverse.
    EXPECT_NEAR(dirpoleEnergyScale(1.0, 1.0), 1.0 / 1.3395, 1e-3);
    EXPECT_NEAR(dirpoleEnergyScale(1.0, 1.0, EnergyTarget::BetterDipole), 1.0 / 1.3395, 1e-3);
    EXPECT_THROW(dirpoleEnergyScale(-0.1, 1.3), ValueError);
    EXPECT_THROW(dirpoleEnergyScale(1.1, 1.3), ValueError);
    EXPECT_THROW(dirpoleEnergyScale(NAN, 1.3), ValueError);
    EXPECT_THROW(dirpoleEnergyScale(0.5, 0.9), ValueError);
    EXPECT_THROW(DirpoleEnergyTable(3.5), ValueError);
    EXPECT_THROW(DirectionalDipole(0.1, 1.0, 1.3, -1.0), ValueError);
    EXPECT_EQ(DirpoleEnergyTable().scale(0.5), 1.0);  // empty table: the published model
}
