// SPDX-License-Identifier: MIT
#include <lucent/core/Fresnel.h>
#include <lucent/sslpv/Transfer.h>

#include <lucent/core/Error.h>
#include <lucent/core/SphericalHarmonics.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace lucent;
using namespace lucent::sslpv;

// The paper prints the ±x matrix to 3 decimals (§4); rounding gives ±5e-4. The 24-node
// Gauss–Legendre rule on a smooth integrand is accurate to ~1e-10, float storage to 1e-7.
constexpr float PRINTED_TOL = 5e-4f;

TEST(SslpvTransfer, ReproducesPrintedXMatrix) {
    for (int sign : {+1, -1}) {
        const PropagationMatrix m = computePropagationMatrix(1, 0, sign);
        const float s = float(sign);  // upper sign of ∓ belongs to the source at d + x
        const float expected[4][4] = {{0.167f, 0.f, 0.f, -s * 0.240f},
                                      {0.f, 0.070f, 0.f, 0.f},
                                      {0.f, 0.f, 0.070f, 0.f},
                                      {-s * 0.037f, 0.f, 0.f, 0.062f}};
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j)
                EXPECT_NEAR(m.at(i, j), expected[i][j], PRINTED_TOL)
                    << "sign " << sign << " entry " << i << "," << j;
    }
}

TEST(SslpvTransfer, QuadratureConverged) {
    // 24 vs 48 nodes agree far below the printed precision: the integrand is analytic on the
    // face (the source centre is at least half a cell away).
    for (int order : {1, 2}) {
        const PropagationMatrix a = computePropagationMatrix(order, 2, -1, 24);
        const PropagationMatrix b = computePropagationMatrix(order, 2, -1, 48);
        for (size_t k = 0; k < a.m.size(); ++k)
            EXPECT_NEAR(a.m[k], b.m[k], 1e-6f);
    }
}

TEST(SslpvTransfer, OtherAxesArePermutations) {
    // y and z matrices: the x row/column (index 3) swapped with y (1) or z (2), §4.
    const auto& mats = propagationMatrices(1);
    const int axisCoeff[3] = {3, 1, 2};
    for (int sign : {+1, -1}) {
        const PropagationMatrix& mx = mats[neighbourIndex(0, sign)];
        for (int axis = 1; axis < 3; ++axis) {
            const PropagationMatrix& m = mats[neighbourIndex(axis, sign)];
            auto perm = [&](int i) {
                if (i == 3)
                    return axisCoeff[axis];
                if (i == axisCoeff[axis])
                    return 3;
                return i;
            };
            for (int i = 0; i < 4; ++i)
                for (int j = 0; j < 4; ++j)
                    EXPECT_NEAR(m.at(perm(i), perm(j)), mx.at(i, j), 1e-6f)
                        << "axis " << axis << " sign " << sign;
        }
    }
}

TEST(SslpvTransfer, FluxIsConservedAcrossSixNeighbours) {
    // Rays from a cell centre leave through exactly one neighbour and then exactly one of its
    // five non-shared faces, so the 30 face solid angles tile 4π: Σ_o M_o[0][0] = 1 and the
    // dipole terms cancel pairwise. This is what makes propagation energy-conserving.
    for (int order : {1, 2}) {
        const auto& mats = propagationMatrices(order);
        const int count = shCount(order);
        for (int j = 0; j < count; ++j) {
            double sum = 0.0;
            for (const auto& m : mats)
                sum += m.at(0, j);
            EXPECT_NEAR(sum, j == 0 ? 1.0 : 0.0, 1e-6) << "order " << order << " column " << j;
        }
    }
}

TEST(SslpvTransfer, Order2ContainsOrder1) {
    const auto& m1 = propagationMatrices(1);
    const auto& m2 = propagationMatrices(2);
    for (int o = 0; o < 6; ++o)
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j)
                EXPECT_NEAR(m1[o].at(i, j), m2[o].at(i, j), 1e-7f);
}

TEST(SslpvTransfer, RejectsBadArguments) {
    EXPECT_THROW(computePropagationMatrix(3, 0, 1), ValueError);
    EXPECT_THROW(computePropagationMatrix(1, 3, 1), ValueError);
    EXPECT_THROW(computePropagationMatrix(1, 0, 0), ValueError);
    EXPECT_THROW(propagationMatrices(0), ValueError);
}

TEST(SslpvTransfer, FresnelLimits) {
    // Normal incidence: ((η−1)/(η+1))²; η = 1: no reflection; grazing: total reflection.
    EXPECT_NEAR(fresnelDielectric(1.f, 1.5f), 0.04f, 1e-6f);
    EXPECT_NEAR(fresnelDielectric(0.3f, 1.f), 0.f, 1e-6f);
    EXPECT_NEAR(fresnelDielectric(0.f, 1.5f), 1.f, 1e-6f);
    // From inside (η < 1) beyond the critical angle: total internal reflection.
    EXPECT_EQ(fresnelDielectric(0.2f, 1.f / 1.5f), 1.f);
    for (float c = 0.f; c <= 1.f; c += 0.05f) {
        const float f = fresnelDielectric(c, 2.5f);
        EXPECT_GE(f, 0.f);
        EXPECT_LE(f, 1.f);
    }
}

TEST(SslpvTransfer, SnellRefraction) {
    const Normal3f n(0.f, 0.f, 1.f);
    const float theta = 0.6f;
    const Vector3f wi(std::sin(theta), 0.f, -std::cos(theta));
    const Vector3f wt = refractInto(wi, n, 1.5f);
    EXPECT_NEAR(glm::length(wt), 1.f, 1e-6f);
    EXPECT_LT(wt.z, 0.f);
    EXPECT_NEAR(wt.x, std::sin(theta) / 1.5f, 1e-6f);  // η sin θt = sin θi
    const Vector3f same = refractInto(wi, n, 1.f);
    EXPECT_NEAR(glm::distance(same, wi), 0.f, 1e-6f);
}

TEST(SslpvTransfer, RsmSolidAnglesCoverCube) {
    // Six 90° faces of a cube map cover 4π. The per-texel formula is the midpoint rule of the
    // exact integral, error O(1/N²): for N = 64 the relative error is ~1e-4.
    const int n = 64;
    for (float nearPlane : {0.01f, 1.f, 50.f}) {
        double total = 0.0;
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const float u = (2.f * (x + 0.5f) / n - 1.f), v = (2.f * (y + 0.5f) / n - 1.f);
                const float cosT = 1.f / std::sqrt(1.f + u * u + v * v);
                total += rsmTexelSolidAngle(1.f, 1.f, n, n, cosT, nearPlane);
            }
        EXPECT_NEAR(6.0 * total, 4.0 * PI, 4.0 * PI * 5e-4) << "near " << nearPlane;
    }
}
