// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/material/Resample.h>

#include "TestUtil.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace lucent;
using lucent::test::unitGrid;

namespace {
const MaterialSample UNIFORM{Rgb(0.7f, 1.3f, 2.f), Rgb(0.5f, 0.3f, 1.9f), Rgb(0.3f, 0.f, -0.2f)};
}

TEST(Resample, UniformVolumeKeepsSigma) {
    MaterialVolume v(unitGrid(32), UNIFORM);
    for (int res : {32, 8, 5, 1}) {  // 5 does not divide 32: fractional overlaps
        SCOPED_TRACE(res);
        const CoarseMaterial c = resampleForPropagation(v, res);
        EXPECT_EQ(c.spec.resolution, res);
        EXPECT_FLOAT_EQ(c.spec.voxelSize, 32.f / float(res));
        EXPECT_TRUE(c.homogeneous);
        for (size_t i = 0; i < c.spec.voxelCount(); ++i)
            for (int ch = 0; ch < 3; ++ch) {
                // Each column's τ is a sum of ≤ 33 terms in double, −ln(e^{−τ})/H is exact to
                // ~1e-15 relative; the float result is within 2 ulp (≈ 2.4e-7 relative).
                ASSERT_NEAR(c.sigma_t[ch][i], UNIFORM.sigma_t[ch], 1e-6f * UNIFORM.sigma_t[ch]);
                ASSERT_NEAR(c.sigma_s[ch][i], UNIFORM.sigma_s[ch], 1e-6f * UNIFORM.sigma_t[ch]);
                ASSERT_NEAR(c.g[ch][i], UNIFORM.g[ch], 1e-6f);
                ASSERT_NEAR(c.insideFraction[i], 1.f, 1e-6f);
            }
    }
}

TEST(Resample, HalfEmptyCellPreservesMeanTransmittance) {
    const int n = 32;
    const float sigma = 0.05f;  // mm⁻¹; τ across a 32 mm cell = 1.6 (neither thin nor opaque)
    MaterialVolume v(unitGrid(n),
                     {Rgb(sigma, 2.f * sigma, 4.f * sigma), Rgb(0.5f * sigma), Rgb(0.f)});
    // 15 inside layers and the skin layer next to them (BoundarySkin.h): material in half the
    // cell, x < 16.
    std::vector<uint8_t> mask(v.spec().voxelCount(), 0);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n / 2 - 1; ++x)
                mask[v.spec().linearIndex({x, y, z})] = 1;
    v.setInsideMask(mask);
    const CoarseMaterial c = resampleForPropagation(v, 1);
    const double H = 32.0;
    for (int ch = 0; ch < 3; ++ch) {
        const double s = double(v.at({0, 0, 0}).sigma_t[ch]);
        // Fine columns along x all cross 16 mm of material: T = e^{−16σ}. Along y and z half
        // the columns cross 32 mm of material and half cross none: T = (1 + e^{−32σ})/2.
        const double tx = std::exp(-s * H / 2.0);
        const double tyz = 0.5 * (1.0 + std::exp(-s * H));
        const double mean = (tx + 2.0 * tyz) / 3.0;
        // σt,eff is stored as float (relative error 6e-8): T is off by ≤ τ·6e-8 ≈ 1e-7.
        EXPECT_NEAR(std::exp(-double(c.sigma_t[ch][0]) * H), mean, 1e-6);
        // …which is not what the naive mean σ (σ/2) would give.
        EXPECT_GT(std::abs(std::exp(-0.5 * s * H) - mean), 1e-3);
        // Albedo of the material is kept: σs′/σt = 0.5σ / σt,fine.
        EXPECT_NEAR(c.sigma_s[ch][0] / c.sigma_t[ch][0], 0.5 * sigma / s, 1e-6);
    }
    EXPECT_NEAR(c.insideFraction[0], 0.5f, 1e-6f);
    EXPECT_TRUE(resampleForPropagation(v, 4).homogeneous);   // cells are full or empty
    EXPECT_FALSE(resampleForPropagation(v, 3).homogeneous);  // the middle cell is partial
    const CoarseMaterial c2 = resampleForPropagation(v, 2);
    EXPECT_EQ(c2.insideFraction[c2.spec.linearIndex({1, 0, 0})], 0.f);
    EXPECT_EQ(c2.sigma_t[0][c2.spec.linearIndex({1, 0, 0})], 0.f);
    EXPECT_NEAR(c2.sigma_t[0][c2.spec.linearIndex({0, 1, 1})], sigma, 1e-6f * sigma);
}

TEST(Resample, OpaqueCellsDoNotUnderflow) {
    MaterialVolume v(unitGrid(16), {Rgb(1e4f), Rgb(0.f), Rgb(0.f)});
    const CoarseMaterial c = resampleForPropagation(v, 2);  // τ = 8e4 per cell: e^{−τ} = 0
    EXPECT_NEAR(c.sigma_t[0][0], 1e4f, 1e-2f);
}

TEST(Resample, ScatteringWeightedG) {
    MaterialVolume v(unitGrid(16), {Rgb(1.f), Rgb(0.25f), Rgb(0.8f)});
    for (int z = 0; z < 16; ++z)
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 8; ++x)
                v.set({x, y, z}, {Rgb(1.f), Rgb(0.75f), Rgb(-0.4f)});
    const CoarseMaterial c = resampleForPropagation(v, 1);
    // σs′-weighted mean g over equal halves: (0.75·(−0.4) + 0.25·0.8) / (0.75 + 0.25).
    EXPECT_NEAR(c.g[0][0], (0.75f * -0.4f + 0.25f * 0.8f) / 1.f, 1e-6f);
    EXPECT_NEAR(c.sigma_s[0][0], 0.5f, 1e-6f);  // albedo ½ × σt 1
}

TEST(Resample, InvalidResolutionThrows) {
    MaterialVolume v(unitGrid(16), UNIFORM);
    EXPECT_THROW(resampleForPropagation(v, 0), ValueError);
    EXPECT_THROW(resampleForPropagation(v, 17), ValueError);
    EXPECT_THROW(resampleForPropagation(MaterialVolume(), 4), ValueError);
}

namespace {

/// The fraction of each coarse cell of a res³ grid over v's box in inside voxels, by exact
/// 1-D overlaps (fractional ratios included), x fastest.
std::vector<double> maskFractions(const MaterialVolume& v, int res) {
    const int n = v.resolution();
    const double r = double(n) / double(res);
    const auto overlap = [&](int I, int i) {
        return std::max(0.0, std::min(double(i + 1), (I + 1) * r) - std::max(double(i), I * r));
    };
    std::vector<double> out(size_t(res) * res * res, 0.0);
    for (int K = 0; K < res; ++K)
        for (int J = 0; J < res; ++J)
            for (int I = 0; I < res; ++I) {
                double sum = 0.0;
                for (int z = 0; z < n; ++z)
                    for (int y = 0; y < n; ++y)
                        for (int x = 0; x < n; ++x)
                            if (v.isInside({x, y, z}))
                                sum += overlap(I, x) * overlap(J, y) * overlap(K, z);
                out[(size_t(K) * res + size_t(J)) * res + size_t(I)] = sum / (r * r * r);
            }
    return out;
}

}  // namespace

TEST(Resample, AnyCoarseCellInsideReadsTheMasksFractions) {
    // anyCoarseCellInside answers from the inside mask alone (not its skin: the mask samples the
    // mesh's own fraction, which SSLPV's cells keep), at every threshold: a slab whose thickness
    // (2 of 32 fine voxels) is under half a cell of the coarser grids, and one thick enough, at
    // divisible and fractional ratios.
    for (int thickness : {2, 5}) {
        MaterialVolume v(unitGrid(32), UNIFORM);
        std::vector<uint8_t> mask(size_t(32) * 32 * 32, 0);
        for (int z = 13; z < 13 + thickness; ++z)
            for (int y = 0; y < 32; ++y)
                for (int x = 0; x < 32; ++x)
                    mask[(size_t(z) * 32 + size_t(y)) * 32 + size_t(x)] = 1;
        v.setInsideMask(mask);
        for (int res : {32, 16, 8, 5, 3}) {
            const std::vector<double> f = maskFractions(v, res);
            const float largest = float(*std::max_element(f.begin(), f.end()));
            for (float fraction : {0.1f, 0.25f, 0.5f, 0.75f, 1.f}) {
                SCOPED_TRACE(testing::Message() << "thickness " << thickness << ", grid " << res
                                                << ", fraction " << fraction);
                // Exact sums of dyadic or short overlaps: away from the threshold by > 1e-6.
                if (std::abs(largest - fraction) > 1e-6f) {
                    EXPECT_EQ(anyCoarseCellInside(v, res, fraction), largest >= fraction);
                }
            }
            EXPECT_FALSE(anyCoarseCellInside(v, res, largest + 1e-5f));
        }
    }
    // A slab of fine layers 15–16: half of grid 16's cells 14–15 and 16–17, but a quarter of
    // grid 8's 12–15 and 16–19, so nothing to read there.
    MaterialVolume v(unitGrid(32), UNIFORM);
    std::vector<uint8_t> mask(size_t(32) * 32 * 32, 0);
    for (size_t i = size_t(15) * 32 * 32; i < size_t(17) * 32 * 32; ++i)
        mask[i] = 1;
    v.setInsideMask(mask);
    EXPECT_TRUE(anyCoarseCellInside(v, 16, 0.5f));
    EXPECT_FALSE(anyCoarseCellInside(v, 8, 0.5f));
    EXPECT_THROW((void)anyCoarseCellInside(v, 33, 0.5f), ValueError);
}

TEST(Resample, TheSkinCarriesTheMaterialPastTheMask) {
    // The mesh reaches up to half a voxel past the inside mask (voxel centres decide it): the
    // voxels next to the mask hold the boundary skin's value (BoundarySkin.h), the medium the
    // reference renders there, so a renderer bounding cells by the mesh finds material in them.
    const MaterialSample dense{Rgb(2.f, 3.f, 4.f), Rgb(1.5f, 2.f, 1.f), Rgb(0.5f, 0.f, -0.3f)};
    MaterialVolume v(unitGrid(16), UNIFORM);
    std::vector<uint8_t> mask(v.spec().voxelCount(), 0);
    for (int z = 4; z < 12; ++z)
        for (int y = 4; y < 12; ++y)
            for (int x = 4; x < 12; ++x)
                mask[v.spec().linearIndex({x, y, z})] = 1;
    v.setInsideMask(mask);
    for (int z = 4; z < 12; ++z)
        for (int y = 4; y < 12; ++y)
            v.set({4, y, z}, dense);  // the face x = 4 painted dense
    const CoarseMaterial c = resampleForPropagation(v, 16);
    const auto expectSample = [&](const Coord& q, const MaterialSample& m, float fraction) {
        SCOPED_TRACE(testing::Message() << "cell " << q.x << "," << q.y << "," << q.z);
        const size_t k = c.spec.linearIndex(q);
        EXPECT_EQ(c.insideFraction[k], fraction);
        for (int ch = 0; ch < 3; ++ch) {
            EXPECT_NEAR(c.sigma_t[ch][k], m.sigma_t[ch], 1e-6f * m.sigma_t[ch]);
            EXPECT_NEAR(c.sigma_s[ch][k], m.sigma_s[ch], 1e-6f * m.sigma_t[ch]);
            EXPECT_NEAR(c.g[ch][k], m.g[ch], 1e-6f);
        }
    };
    expectSample({3, 6, 6}, dense, 1.f);     // beside the dense face: its value
    expectSample({12, 6, 6}, UNIFORM, 1.f);  // beside the far face
    expectSample({2, 6, 6}, {}, 0.f);        // two voxels out: no material
    // Homogeneous material stays homogeneous with its skin (each ring of equal values gives that
    // value exactly).
    MaterialVolume u(unitGrid(16), UNIFORM);
    u.setInsideMask(mask);
    EXPECT_TRUE(resampleForPropagation(u, 16).homogeneous);
}
