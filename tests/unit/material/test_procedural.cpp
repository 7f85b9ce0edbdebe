// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/core/Random.h>
#include <lucent/material/History.h>
#include <lucent/material/Procedural.h>

#include "TestUtil.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace lucent;
using lucent::test::bitEqual;
using lucent::test::rawBricks;
using lucent::test::unitGrid;

namespace {
const MaterialSample A{Rgb(1.f, 2.f, 3.f), Rgb(0.5f, 1.f, 1.5f), Rgb(0.f)};
const MaterialSample B{Rgb(4.f, 0.5f, 1.f), Rgb(3.f, 0.2f, 1.f), Rgb(0.5f)};
}  // namespace

TEST(Procedural, DistanceTransformMatchesBruteForce) {
    const int n = 12;
    MaterialVolume v(unitGrid(n), A);
    v.setInsideMask(std::vector<uint8_t>(size_t(n) * n * n, 1));
    {
        // Full box: the nearest outside voxel centre is in the padding layer, straight along an
        // axis.
        const std::vector<float> d = distanceToSurface(v);
        for (int z = 0; z < n; ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const int m = std::min({x + 1, n - x, y + 1, n - y, z + 1, n - z});
                    ASSERT_FLOAT_EQ(d[v.spec().linearIndex({x, y, z})], float(m) - 0.5f);
                }
    }
    // Random mask: compare with the minimum over every outside voxel and the padding.
    Pcg32 rng(3);
    std::vector<uint8_t> mask(size_t(n) * n * n);
    for (auto& m : mask)
        m = rng.uniform() < 0.93f;
    v.setInsideMask(mask);
    const std::vector<float> d = distanceToSurface(v);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const size_t i = v.spec().linearIndex({x, y, z});
                if (!mask[i]) {
                    EXPECT_EQ(d[i], 0.f);
                    continue;
                }
                double best = std::min({x + 1, n - x, y + 1, n - y, z + 1, n - z});
                for (int k = 0; k < n; ++k)
                    for (int j = 0; j < n; ++j)
                        for (int l = 0; l < n; ++l)
                            if (!mask[v.spec().linearIndex({l, j, k})])
                                best = std::min(
                                    best, std::sqrt(double((l - x) * (l - x) + (j - y) * (j - y) +
                                                           (k - z) * (k - z))));
                ASSERT_NEAR(d[i], best - 0.5, 1e-5) << x << " " << y << " " << z;
            }
}

TEST(Procedural, NoiseProperties) {
    // Gradient noise vanishes on the integer lattice (Perlin 2002) and stays in about [−1, 1].
    float lo = 0.f, hi = 0.f;
    for (int i = 0; i < 5; ++i)
        EXPECT_EQ(gradientNoise(Point3f(float(i), float(2 * i), -3.f), 9), 0.f);
    Pcg32 rng(1);
    for (int i = 0; i < 20000; ++i) {
        const Point3f p(50.f * rng.uniform(), 50.f * rng.uniform(), 50.f * rng.uniform());
        const float v = gradientNoise(p, 9);
        lo = std::min(lo, v);
        hi = std::max(hi, v);
        const float t = turbulence(p, 4, 9);
        ASSERT_TRUE(t >= 0.f && t <= 1.f);
    }
    EXPECT_LT(lo, -0.3f);  // not degenerate
    EXPECT_GT(hi, 0.3f);
    EXPECT_GE(lo, -1.1f);
    EXPECT_LE(hi, 1.1f);
    EXPECT_NE(gradientNoise(Point3f(0.3f, 0.4f, 0.5f), 1),
              gradientNoise(Point3f(0.3f, 0.4f, 0.5f), 2));
}

TEST(Procedural, LayeredFillFollowsDepth) {
    const int n = 24;
    MaterialVolume v(unitGrid(n), A);
    ProceduralFill f;
    f.pattern = ProceduralPattern::Layered;
    f.amplitude = 0.f;
    f.layers = {{3.f, A}, {2.f, B}, {1.f, sanitize({Rgb(7.f), Rgb(7.f), Rgb(0.f)})}};
    fillProcedural(v, f);
    const std::vector<float> depth = distanceToSurface(v);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const float d = depth[v.spec().linearIndex({x, y, z})];
                const MaterialSample want = d < 3.f ? A : d < 5.f ? B : f.layers[2].material;
                ASSERT_EQ(v.at({x, y, z}), want) << d;
            }
}

TEST(Procedural, MarbleAndTurbulenceBlendBetweenMaterials) {
    for (ProceduralPattern pat : {ProceduralPattern::Marble, ProceduralPattern::Turbulence}) {
        MaterialVolume v(unitGrid(32), A);
        ProceduralFill f;
        f.pattern = pat;
        f.materialA = A;
        f.materialB = B;
        f.scale = 8.f;
        f.seed = 11;
        History h;
        h.beginStroke(v);
        fillProcedural(v, f, &h);
        h.endStroke(v);
        float minT = 1e9f, maxT = -1e9f;
        for (int z = 0; z < 32; ++z)
            for (int y = 0; y < 32; ++y)
                for (int x = 0; x < 32; ++x) {
                    const MaterialSample s = v.at({x, y, z});
                    // Every value lies between A and B (a convex blend), σs′ ≤ σt kept.
                    for (int c = 0; c < 3; ++c) {
                        ASSERT_GE(s.sigma_t[c], std::min(A.sigma_t[c], B.sigma_t[c]) - 1e-5f);
                        ASSERT_LE(s.sigma_t[c], std::max(A.sigma_t[c], B.sigma_t[c]) + 1e-5f);
                        ASSERT_LE(s.sigma_s[c], s.sigma_t[c]);
                    }
                    minT = std::min(minT, s.sigma_t.r);
                    maxT = std::max(maxT, s.sigma_t.r);
                }
        EXPECT_GT(maxT - minT, 0.3f * (B.sigma_t.r - A.sigma_t.r)) << "pattern has no contrast";
        // Deterministic for a seed, different for another.
        MaterialVolume w(unitGrid(32), A);
        fillProcedural(w, f);
        EXPECT_TRUE(bitEqual(rawBricks(v), rawBricks(w)));
        f.seed = 12;
        fillProcedural(w, f);
        EXPECT_FALSE(bitEqual(rawBricks(v), rawBricks(w)));
        // Undoable like any stroke.
        h.undo(v);
        EXPECT_TRUE(v.isHomogeneous());
    }
}

TEST(Procedural, InvalidParametersThrow) {
    MaterialVolume v(unitGrid(16), A);
    auto bad = [&](auto edit) {
        ProceduralFill f;
        f.materialA = A;
        f.materialB = B;
        edit(f);
        EXPECT_THROW(fillProcedural(v, f), ValueError);
    };
    bad([](ProceduralFill& f) { f.scale = 0.f; });
    bad([](ProceduralFill& f) { f.scale = std::nanf(""); });
    bad([](ProceduralFill& f) { f.octaves = 0; });
    bad([](ProceduralFill& f) { f.amplitude = -1.f; });
    bad([](ProceduralFill& f) { f.sharpness = 0.f; });
    bad([](ProceduralFill& f) { f.channels = 0; });
    bad([](ProceduralFill& f) { f.materialB.sigma_t.r = std::nanf(""); });
    bad([](ProceduralFill& f) { f.materialA.g.r = 3.f; });
    bad([](ProceduralFill& f) {
        f.pattern = ProceduralPattern::Marble;
        f.direction = Vector3f(0.f);
    });
    bad([](ProceduralFill& f) { f.pattern = ProceduralPattern::Layered; });
    bad([](ProceduralFill& f) {
        f.pattern = ProceduralPattern::Layered;
        f.layers = {{-1.f, A}};
    });
    EXPECT_THROW(turbulence(Point3f(0.f), 0, 1), ValueError);
    EXPECT_TRUE(v.isHomogeneous());
}
