// SPDX-License-Identifier: MIT
// The adding–doubling half-space solver (lucent/dipole/HalfSpace.h) against closed forms and an
// independent Monte Carlo.
#include <lucent/core/Error.h>
#include <lucent/core/Quadrature.h>
#include <lucent/dipole/HalfSpace.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
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

/// Fresnel reflectance of unpolarised light leaving a medium of index η into index 1 at the
/// inside cosine c (1 past the critical angle). Written here so that the slab's Monte Carlo
/// shares nothing with the solver.
double leavingFresnel(double c, double eta) {
    const double sinT = eta * std::sqrt(std::max(0.0, 1.0 - c * c));
    if (sinT >= 1.0)
        return 1.0;
    const double t = std::sqrt(1.0 - sinT * sinT);
    const double rs = (eta * c - t) / (eta * c + t), rp = (c - eta * t) / (c + eta * t);
    return 0.5 * (rs * rs + rp * rp);
}

/// Analog Monte Carlo of a slab (σt = 1, isotropic scattering of albedo a as a weight, the same
/// index η on both faces, each face reflecting by leavingFresnel and letting the rest out): the
/// means and standard errors of the four parts of SlabExitance per unit entering flux.
struct SlabTally {
    double mean[4] = {}, error[4] = {};  // reflectance, transmittance, direct T, direct R
};
SlabTally slabMonteCarlo(double a, double eta, double tau, double mu0, int photons, uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    double sum[4] = {}, sumSq[4] = {};
    for (int p = 0; p < photons; ++p) {
        double z = 0.0, mu = mu0, weight = 1.0;
        bool scattered = false;
        for (;;) {
            const double next = z - std::log(1.0 - uniform(rng)) * mu;
            if (next < 0.0 || next > tau) {
                const bool bottom = next > tau;
                z = bottom ? tau : 0.0;
                if (uniform(rng) < leavingFresnel(std::abs(mu), eta)) {
                    mu = -mu;  // reflected back in; the free path starts again (memoryless)
                    continue;
                }
                const int part = scattered ? (bottom ? 1 : 0) : (bottom ? 2 : 3);
                sum[part] += weight;
                sumSq[part] += weight * weight;
                break;
            }
            z = next;
            weight *= a;
            scattered = true;
            mu = 2.0 * uniform(rng) - 1.0;
            if (weight < 1e-3) {  // Russian roulette, unbiased
                if (uniform(rng) >= 0.1)
                    break;
                weight *= 10.0;
            }
        }
    }
    SlabTally t;
    for (int k = 0; k < 4; ++k) {
        t.mean[k] = sum[k] / photons;
        t.error[k] = std::sqrt(std::max(0.0, sumSq[k] / photons - t.mean[k] * t.mean[k]) / photons);
    }
    return t;
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

TEST(SlabExitance, AgreesWithAnIndependentMonteCarlo) {
    // Thin to thick slabs at the default scene's η = 1.4 and η = 1.3, head-on and oblique, at a
    // mid albedo (skin1's green) and a high one; 4·10⁵ photons each. Tolerance: 5 standard
    // errors of the tally plus the adding–doubling's quadrature error (3·10⁻⁵, NodeCountConverges).
    struct Case {
        double a, eta, tau, mu0;
    };
    const Case cases[] = {{0.838, 1.4, 0.5, 1.0}, {0.838, 1.4, 1.0, 1.0}, {0.838, 1.4, 2.0, 1.0},
                          {0.838, 1.4, 4.0, 1.0}, {0.99, 1.3, 1.0, 1.0},  {0.68, 1.3, 1.5, 0.6},
                          {0.95, 1.0, 0.8, 0.8}};
    uint64_t seed = 1;
    for (const Case& c : cases) {
        const SlabExitance exact = slabExitance(c.a, c.eta, c.tau, c.mu0);
        const SlabTally mc = slabMonteCarlo(c.a, c.eta, c.tau, c.mu0, 400000, seed++);
        const double solved[4] = {exact.reflectance, exact.transmittance, exact.directTransmittance,
                                  exact.directReflectance};
        for (int k = 0; k < 4; ++k)
            EXPECT_NEAR(solved[k], mc.mean[k], 5.0 * mc.error[k] + 3e-5)
                << "part " << k << " of a " << c.a << ", eta " << c.eta << ", tau " << c.tau
                << ", mu0 " << c.mu0;
    }
}

TEST(SlabExitance, LimitsAndEnergy) {
    // A thick slab is the half-space (200 mean free paths: at α′ = 0.99 the light has decayed
    // by e^(−200·√(3·0.01)) ≈ 10⁻¹⁵; the two doublings start from layers of different
    // thickness, a rounding difference far under the quadrature's 3·10⁻⁵); a conservative
    // slab sends everything out of its two faces.
    for (double eta : {1.0, 1.4})
        for (double a : {0.3, 0.84, 0.99}) {
            const SlabExitance thick = slabExitance(a, eta, 200.0);
            EXPECT_NEAR(thick.reflectance, halfSpaceReflectance(a, eta), 1e-6) << a;
            EXPECT_LT(thick.transmittance, 1e-9);
        }
    for (double eta : {1.0, 1.4})
        for (double tau : {0.1, 1.0, 5.0})
            for (double mu0 : {1.0, 0.5}) {
                const SlabExitance s = slabExitance(1.0, eta, tau, mu0);
                EXPECT_NEAR(
                    s.reflectance + s.transmittance + s.directTransmittance + s.directReflectance,
                    1.0, 2e-6)
                    << "eta " << eta << ", tau " << tau << ", mu0 " << mu0;
            }
    // Nothing scatters: only the beam, bouncing between the faces.
    const SlabExitance dark = slabExitance(0.0, 1.4, 1.0, 0.8);
    EXPECT_EQ(dark.reflectance, 0.0);
    EXPECT_EQ(dark.transmittance, 0.0);
    const double f = leavingFresnel(0.8, 1.4), d = std::exp(-1.0 / 0.8);
    EXPECT_NEAR(dark.directTransmittance, (1.0 - f) * d / (1.0 - f * f * d * d), 1e-6);
    EXPECT_NEAR(dark.directReflectance, (1.0 - f) * f * d * d / (1.0 - f * f * d * d), 1e-6);
    EXPECT_THROW(slabExitance(0.5, 1.3, -1.0), ValueError);
    EXPECT_THROW(slabExitance(0.5, 1.3, INFINITY), ValueError);
    EXPECT_THROW(slabExitance(1.5, 1.3, 1.0), ValueError);
}

TEST(SlabExitance, ExitRadianceIntegratesToEachFacesExitance) {
    // As HalfSpace.ExitRadianceIntegratesToTheReflectance, for both faces of thin and thick
    // slabs; a thick slab's reflected radiance is the half-space's.
    const QuadratureRule g = gaussLegendre(64).mappedTo(0.0, 1.0);
    for (double eta : {1.0, 1.4})
        for (double tau : {0.5, 2.0})
            for (double a : {0.68, 0.96}) {
                const SlabExitance e = slabExitance(a, eta, tau, 1.0, g.x);
                double reflected = 0.0, transmitted = 0.0;
                for (size_t k = 0; k < g.x.size(); ++k) {
                    reflected += 2.0 * M_PI * g.w[k] * g.x[k] * e.reflectedRadiance[k];
                    transmitted += 2.0 * M_PI * g.w[k] * g.x[k] * e.transmittedRadiance[k];
                }
                SCOPED_TRACE(testing::Message() << "eta " << eta << " tau " << tau << " a " << a);
                EXPECT_NEAR(reflected, e.reflectance, 3e-5);
                EXPECT_NEAR(transmitted, e.transmittance, 3e-5);
                EXPECT_NEAR(e.transmittance, slabExitance(a, eta, tau).transmittance, 1e-10);
            }
    const std::vector<double> cosines = {1.0, 0.5, 0.1};
    const SlabExitance thick = slabExitance(0.9, 1.4, 200.0, 1.0, cosines);
    const HalfSpaceExitance halfSpace = halfSpaceExitance(0.9, 1.4, 1.0, cosines);
    for (size_t k = 0; k < cosines.size(); ++k)
        EXPECT_NEAR(thick.reflectedRadiance[k], halfSpace.radiance[k], 1e-6) << cosines[k];
    EXPECT_THROW(slabExitance(0.5, 1.3, 1.0, 1.0, {0.0}), ValueError);
}
