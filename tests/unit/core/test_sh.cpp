// SPDX-License-Identifier: MIT
#include <lucent/core/SphericalHarmonics.h>
#include <lucent/core/Random.h>
#include <lucent/core/Sampling.h>

#include <gtest/gtest.h>

using namespace lucent;

// Quadrature error of a 20k-point Fibonacci sphere on degree ≤ 4 polynomials is O(1/N) ≈ 1e-4;
// float accumulation adds ~1e-6. Tolerance 5e-4 covers both.
constexpr float QUAD_TOL = 5e-4f;

TEST(SphericalHarmonics, OrthonormalByQuadrature) {
    for (int i = 0; i < 9; ++i) {
        for (int j = 0; j < 9; ++j) {
            auto proj = shProject<2>([&](const Vector3f& w) {
                float y[9];
                shEvaluate(2, w, y);
                return y[i] * y[j];
            });
            // ∫ Y_i Y_j dω = δ_ij is the Y00 coefficient of Y_i Y_j times 1/Y00 = 2√π.
            const float integral = proj.c[0] * 2.f * std::sqrt(PI);
            EXPECT_NEAR(integral, i == j ? 1.f : 0.f, QUAD_TOL) << i << "," << j;
        }
    }
}

TEST(SphericalHarmonics, ClampedCosineZonalMatchesQuadrature) {
    auto proj = shProject<2>([](const Vector3f& w) { return std::max(0.f, w.z); }, 200000);
    EXPECT_NEAR(proj.c[0], std::sqrt(PI) / 2.f, 1e-4f);
    EXPECT_NEAR(proj.c[2], std::sqrt(PI / 3.f), 1e-4f);
    EXPECT_NEAR(proj.c[6], std::sqrt(5.f * PI) / 8.f, 1e-4f);
    EXPECT_FLOAT_EQ(clampedCosineZonal(0), std::sqrt(PI) / 2.f);
    EXPECT_FLOAT_EQ(clampedCosineZonal(1), std::sqrt(PI / 3.f));
}

TEST(SphericalHarmonics, RotatedLobeEqualsProjectionOfRotatedFunction) {
    Pcg32 rng(7);
    for (int t = 0; t < 10; ++t) {
        const Vector3f axis = sampleUniformSphere({rng.uniform(), rng.uniform()});
        const auto rotated = clampedCosineLobe<2>(axis);
        const auto projected = shProject<2>(
            [&](const Vector3f& w) { return std::max(0.f, glm::dot(w, axis)); }, 200000);
        for (int i = 0; i < 9; ++i)
            EXPECT_NEAR(rotated.c[i], projected.c[i], 2e-4f) << i;
    }
}

TEST(SphericalHarmonics, BandEnergyIsRotationInvariant) {
    Pcg32 rng(11);
    float z[3] = {0.3f, -0.7f, 0.45f};
    const auto ref = rotateZonal<2>(z, Vector3f(0, 0, 1));
    for (int t = 0; t < 50; ++t) {
        const Vector3f axis = sampleUniformSphere({rng.uniform(), rng.uniform()});
        const auto r = rotateZonal<2>(z, axis);
        for (int l = 0; l <= 2; ++l)
            EXPECT_NEAR(shBandEnergy(r, l), shBandEnergy(ref, l), 1e-5f);
    }
}

TEST(SphericalHarmonics, HgMomentsArePowersOfG) {
    // Legendre moments of HG: 2π∫ p(μ) P_l(μ) dμ = g^l, checked by midpoint quadrature.
    for (float g : {-0.9f, -0.3f, 0.f, 0.5f, 0.8f}) {
        double m1 = 0, m0 = 0;
        const int n = 200000;
        for (int i = 0; i < n; ++i) {
            const double mu = -1.0 + (i + 0.5) * 2.0 / n;
            const double p = hgPhase(g, float(mu));
            m0 += 2 * PI * p * (2.0 / n);
            m1 += 2 * PI * p * mu * (2.0 / n);
        }
        EXPECT_NEAR(m0, 1.0, 2e-3);
        EXPECT_NEAR(m1, hgMoment(g, 1), 2e-3);
        EXPECT_FLOAT_EQ(hgMoment(g, 2), g * g);
    }
}
