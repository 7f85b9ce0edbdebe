// SPDX-License-Identifier: MIT
// The adding–doubling half-space solver (lucent/dipole/HalfSpace.h) against closed forms and an
// independent Monte Carlo.
#include <lucent/core/Error.h>
#include <lucent/core/Quadrature.h>
#include <lucent/dipole/HalfSpace.h>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace lucent;
using namespace lucent::dipole;

namespace {

/// Chandrasekhar's H-function for isotropic scattering of albedo a, from its closed-form
/// integral (Chandrasekhar 1950, "Radiative Transfer", §36, with Ψ = a/2):
///     ln H(μ) = −(μ/π) ∫₀^{π/2} ln(1 − a θ cot θ) / (cos²θ + μ² sin²θ) dθ.
/// The integrand is smooth on [0, π/2] (θ cot θ → 1 at 0, → 0 at π/2), so 400 Gauss–Legendre
/// nodes reach double precision. Shares nothing with the adding–doubling solver.
double chandrasekharH(double a, double mu) {
    const QuadratureRule g = gaussLegendre(400).mappedTo(0.0, 0.5 * M_PI);
    double integral = 0.0;
    for (size_t i = 0; i < g.x.size(); ++i) {
        const double t = g.x[i], c = std::cos(t), s = std::sin(t);
        integral += g.w[i] * std::log(1.0 - a * t * c / s) / (c * c + mu * mu * s * s);
    }
    return std::exp(-mu / M_PI * integral);
}

}  // namespace

TEST(HalfSpace, ChandrasekharHFunctionMatchesItsTabulatedValuesAndMoment) {
    // The check of the check: H(1) = 2.9078 for a = 1 (Chandrasekhar 1950, Table IX), and the
    // zeroth moment ∫₀¹ H dμ = (2/a)(1 − √(1 − a)) (his Eq. 36.(30)) at any albedo.
    EXPECT_NEAR(chandrasekharH(1.0, 1.0), 2.9078, 1e-4);
    const QuadratureRule g = gaussLegendre(64).mappedTo(0.0, 1.0);
    for (double a : {0.3, 0.9, 0.99}) {
        double moment = 0.0;
        for (size_t i = 0; i < g.x.size(); ++i)
            moment += g.w[i] * chandrasekharH(a, g.x[i]);
        // H′ ~ ln μ near 0 limits the 64-node Gauss rule to ≈ 10⁻⁸.
        EXPECT_NEAR(moment, 2.0 / a * (1.0 - std::sqrt(1.0 - a)), 5e-8) << "a = " << a;
    }
}

TEST(HalfSpace, IndexMatchedBoundaryEqualsChandrasekharsClosedForm) {
    // η = 1: the plane albedo of an isotropic half-space lit by a collimated beam at μ₀ is
    // 1 − H(μ₀)√(1 − a) (Chandrasekhar 1950, §47). The solver's only error is its quadrature
    // (HALF_SPACE_NODES) and the first-order start layer (≈ 10⁻⁸); 3·10⁻⁵ absolute is a tenth of
    // what the directional dipole's energy table needs (its interpolation: 5·10⁻⁴ relative).
    for (double a : {0.01, 0.3, 0.68, 0.84, 0.96, 0.999, 0.99999})
        for (double mu0 : {1.0, 0.76, 0.5, 0.15}) {
            const double exact = 1.0 - chandrasekharH(a, mu0) * std::sqrt(1.0 - a);
            EXPECT_NEAR(halfSpaceReflectance(a, 1.0, mu0), exact, 3e-5)
                << "a = " << a << ", mu0 = " << mu0;
        }
    EXPECT_EQ(halfSpaceReflectance(0.0, 1.3), 0.0);
    EXPECT_EQ(halfSpaceReflectance(1.0, 1.3), 1.0);
}

TEST(HalfSpace, DielectricBoundaryAgreesWithAnIndependentMonteCarlo) {
    // η = 1.3, normal incidence, skin1's reduced albedos (σa = 0.032 / 0.17 / 0.48, σs′ = 0.74 /
    // 0.88 / 1.01 mm⁻¹): the exitance per unit entering flux from the analog Monte Carlo of
    // resources/evaluation/skin1-analysis/exact_mc.py (numpy, shares no code with the engine;
    // 2·10⁵ photons per value, standard error ≈ 0.2 % of the value): 0.4388 / 0.2128 / 0.1153.
    // Tolerance: 4 standard errors.
    const double sigmaA[3] = {0.032, 0.17, 0.48}, sigmaS[3] = {0.74, 0.88, 1.01};
    const double monteCarlo[3] = {0.4388, 0.2128, 0.1153};
    for (int c = 0; c < 3; ++c) {
        const double albedo = sigmaS[c] / (sigmaA[c] + sigmaS[c]);
        EXPECT_NEAR(halfSpaceReflectance(albedo, 1.3), monteCarlo[c], 4 * 0.002 * monteCarlo[c])
            << "channel " << c;
    }
}

TEST(HalfSpace, EmergentRadianceEqualsChandrasekharsClosedForm) {
    // η = 1: the radiance an isotropic half-space sends out along μ for a collimated beam at
    // μ₀, per unit entering flux (unit flux per unit area of the surface), is
    // a/(4π) · H(μ)H(μ₀)/(μ + μ₀) (Chandrasekhar 1950, §47, with πF = 1/μ₀). Relative 3·10⁻⁴:
    // the exit directions are exact nodes, the rest is the quadrature's 3·10⁻⁵ on values
    // ≥ 0.1 of the peak.
    const std::vector<double> exits = {1.0, 0.8, 0.5, 0.2, 0.05};
    for (double a : {0.3, 0.68, 0.96, 0.999})
        for (double mu0 : {1.0, 0.5}) {
            const HalfSpaceExitance e = halfSpaceExitance(a, 1.0, mu0, exits);
            ASSERT_EQ(e.radiance.size(), exits.size());
            for (size_t k = 0; k < exits.size(); ++k) {
                const double mu = exits[k];
                const double exact =
                    a / (4.0 * M_PI) * chandrasekharH(a, mu) * chandrasekharH(a, mu0) / (mu + mu0);
                EXPECT_NEAR(e.radiance[k], exact, 3e-4 * exact)
                    << "a " << a << " mu0 " << mu0 << " mu " << mu;
            }
        }
}

TEST(HalfSpace, ExitRadianceIntegratesToTheReflectance) {
    // 2π ∫₀¹ L(t) t dt over the outside cosine = the reflectance (the n² law and the Snell
    // change of variables agree). 64-node Gauss–Legendre in t as the exit directions; the
    // reflectance is the solver's own (8 nodes): 3·10⁻⁵ absolute, as above.
    const QuadratureRule g = gaussLegendre(64).mappedTo(0.0, 1.0);
    for (double eta : {1.0, 1.3, 2.0})
        for (double a : {0.5, 0.9, 0.999, 1.0}) {
            const HalfSpaceExitance e = halfSpaceExitance(a, eta, 1.0, g.x);
            double flux = 0.0;
            for (size_t k = 0; k < g.x.size(); ++k)
                flux += 2.0 * M_PI * g.w[k] * g.x[k] * e.radiance[k];
            EXPECT_NEAR(flux, e.reflectance, 3e-5) << "eta " << eta << " a " << a;
            // Asking for exit directions does not change the solution (to round-off: the LU
            // factors a larger matrix).
            EXPECT_NEAR(e.reflectance, halfSpaceReflectance(a, eta), 1e-10);
        }
}

TEST(HalfSpace, NodeCountConverges) {
    // The default rule against 64 nodes per interval: the difference bounds the quadrature
    // error; 3·10⁻⁵ as above.
    for (double eta : {1.0, 1.3, 3.0})
        for (double a : {0.05, 0.8, 0.99, 0.9999})
            for (double mu0 : {1.0, 0.05}) {
                const double fine = halfSpaceReflectance(a, eta, mu0, 64);
                EXPECT_NEAR(halfSpaceReflectance(a, eta, mu0), fine, 3e-5)
                    << "eta " << eta << " a " << a << " mu0 " << mu0;
            }
}

TEST(HalfSpace, ReflectanceRisesWithAlbedoAndFallsWithIndex) {
    double previous = 0.0;
    for (double a = 0.05; a < 1.0; a += 0.05) {
        const double r = halfSpaceReflectance(a, 1.3);
        EXPECT_GT(r, previous);
        EXPECT_LT(
            r, halfSpaceReflectance(a, 1.0));  // internal reflection returns light to be absorbed
        previous = r;
    }
}

TEST(HalfSpace, RefusesInvalidInput) {
    EXPECT_THROW(halfSpaceReflectance(-0.1, 1.3), ValueError);
    EXPECT_THROW(halfSpaceReflectance(1.1, 1.3), ValueError);
    EXPECT_THROW(halfSpaceReflectance(NAN, 1.3), ValueError);
    EXPECT_THROW(halfSpaceReflectance(0.5, 0.9), ValueError);
    EXPECT_THROW(halfSpaceReflectance(0.5, 1.3, 0.0), ValueError);
    EXPECT_THROW(halfSpaceReflectance(0.5, 1.3, 1.0, 1), ValueError);
    EXPECT_THROW(halfSpaceExitance(0.5, 1.3, 1.0, {0.0}), ValueError);
    EXPECT_THROW(halfSpaceExitance(0.5, 1.3, 1.0, {1.5}), ValueError);
}
