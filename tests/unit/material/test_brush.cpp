// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/core/Random.h>
#include <lucent/material/Brush.h>
#include <lucent/material/History.h>

#include "TestUtil.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>

using namespace lucent;
using lucent::test::ballMask;
using lucent::test::unitGrid;

namespace {

const MaterialSample BASE{Rgb(2.f, 3.f, 4.f), Rgb(1.f, 1.5f, 2.f), Rgb(0.1f, 0.2f, 0.3f)};
// Voxel centres on the x axis through the stamp centre (16.5, 16.5, 16.5), radius 5 mm:
// voxel 16 is the centre (t = 0), voxel 20 is 4 mm away (t = 0.8), voxel 21 is exactly on the
// rim (d = r, not touched).
const Point3f CENTER(16.5f, 16.5f, 16.5f);
const Coord AT_CENTER(16, 16, 16), NEAR_EDGE(20, 16, 16), ON_RIM(21, 16, 16);

BrushSettings baseBrush(BrushMode mode) {
    BrushSettings b;
    b.radius = 5.f;
    b.falloff = Falloff::Linear;
    b.strength = 0.5f;
    b.mode = mode;
    b.channels = ALL_CHANNELS;
    b.value = {Rgb(1.f, 5.f, 2.f), Rgb(0.5f, 0.5f, 1.f), Rgb(0.4f, 0.f, 0.5f)};
    return b;
}

/// The expected value of one component after one stamp of weight w (Brush.h mode table).
float expected(BrushMode m, float v, float u, float base, float w) {
    switch (m) {
        case BrushMode::Set:
            return v + w * (u - v);
        case BrushMode::Add:
            return v + w * u;
        case BrushMode::Subtract:
            return v - w * u;
        case BrushMode::Multiply:
            return v * (1.f + w * (u - 1.f));
        case BrushMode::ResetToBase:
            return v + w * (base - v);
        case BrushMode::Smooth:
            break;
    }
    return NAN;
}

MaterialSample clampLikeSanitize(MaterialSample s) {
    return sanitize(s);
}

}  // namespace

TEST(Brush, FalloffCurves) {
    for (Falloff f : {Falloff::Constant, Falloff::Linear, Falloff::Smooth, Falloff::Gaussian}) {
        EXPECT_FLOAT_EQ(falloffWeight(f, 0.f), 1.f);
        EXPECT_EQ(falloffWeight(f, 1.f), 0.f);
        EXPECT_EQ(falloffWeight(f, 2.f), 0.f);
    }
    EXPECT_FLOAT_EQ(falloffWeight(Falloff::Constant, 0.99f), 1.f);
    EXPECT_FLOAT_EQ(falloffWeight(Falloff::Linear, 0.25f), 0.75f);
    EXPECT_FLOAT_EQ(falloffWeight(Falloff::Smooth, 0.5f), 0.5f);  // smoothstep symmetry
    EXPECT_FLOAT_EQ(falloffWeight(Falloff::Smooth, 0.25f), 1.f - 0.15625f);
    EXPECT_FLOAT_EQ(falloffWeight(Falloff::Gaussian, 1.f / 3.f), std::exp(-0.5f));   // 1σ
    EXPECT_NEAR(falloffWeight(Falloff::Gaussian, 0.9999f), std::exp(-4.5f), 1e-4f);  // 3σ rim
}

TEST(Brush, EveryModeAtCentreAndEdge) {
    for (BrushMode mode : {BrushMode::Set, BrushMode::Add, BrushMode::Subtract, BrushMode::Multiply,
                           BrushMode::ResetToBase}) {
        for (Falloff falloff :
             {Falloff::Constant, Falloff::Linear, Falloff::Smooth, Falloff::Gaussian}) {
            SCOPED_TRACE(int(mode) * 10 + int(falloff));
            MaterialVolume v(unitGrid(32), BASE);
            // A painted starting state that differs from the base, so ResetToBase is visible.
            const MaterialSample start{Rgb(3.f, 6.f, 8.f), Rgb(2.f, 2.f, 2.f),
                                       Rgb(0.f, 0.5f, -0.5f)};
            fillInterior(v, start);
            BrushSettings b = baseBrush(mode);
            b.falloff = falloff;
            if (mode == BrushMode::Multiply)
                b.value = {Rgb(2.f, 0.5f, 1.5f), Rgb(0.25f), Rgb(3.f)};
            stamp(v, b, CENTER);
            for (const auto& [coord, t] : {std::pair{AT_CENTER, 0.f}, std::pair{NEAR_EDGE, 0.8f}}) {
                const float w = b.strength * falloffWeight(falloff, t);
                MaterialSample want;
                for (int c = 0; c < 3; ++c) {
                    want.sigma_t[c] =
                        expected(mode, start.sigma_t[c], b.value.sigma_t[c], BASE.sigma_t[c], w);
                    want.sigma_s[c] =
                        expected(mode, start.sigma_s[c], b.value.sigma_s[c], BASE.sigma_s[c], w);
                    want.g[c] = expected(mode, start.g[c], b.value.g[c], BASE.g[c], w);
                }
                want = clampLikeSanitize(want);
                const MaterialSample got = v.at(coord);
                for (int c = 0; c < 3; ++c) {
                    // Single-precision arithmetic of the same expression: a few ulps.
                    EXPECT_NEAR(got.sigma_t[c], want.sigma_t[c], 1e-5f);
                    EXPECT_NEAR(got.sigma_s[c], want.sigma_s[c], 1e-5f);
                    EXPECT_NEAR(got.g[c], want.g[c], 1e-5f);
                }
            }
            EXPECT_EQ(v.at(ON_RIM), start);             // d = r: untouched
            EXPECT_EQ(v.at(Coord(16, 16, 22)), start);  // outside the ball
        }
    }
}

TEST(Brush, SmoothAveragesTheNeighbourhood) {
    MaterialVolume v(unitGrid(32), BASE);
    MaterialSample spike = BASE;
    spike.sigma_t = Rgb(29.f);
    v.set(AT_CENTER, spike);
    BrushSettings b = baseBrush(BrushMode::Smooth);
    b.channels = uint8_t(Channel::SigmaT);
    b.falloff = Falloff::Constant;
    stamp(v, b, CENTER);
    // Centre: mean of the 3×3×3 box = (26·base + 29)/27, blended with w = 0.5.
    for (int c = 0; c < 3; ++c) {
        const float mean = (26.f * BASE.sigma_t[c] + 29.f) / 27.f;
        EXPECT_NEAR(v.at(AT_CENTER).sigma_t[c], 29.f + 0.5f * (mean - 29.f), 1e-5f);
        // A face neighbour sees the spike once in its 27-box: read before the stamp.
        EXPECT_NEAR(v.at({17, 16, 16}).sigma_t[c],
                    BASE.sigma_t[c] + 0.5f * ((29.f - BASE.sigma_t[c]) / 27.f), 1e-5f);
        EXPECT_EQ(v.at(NEAR_EDGE).sigma_t[c], BASE.sigma_t[c]);  // flat region: unchanged
    }
    EXPECT_EQ(v.at(AT_CENTER).sigma_s, BASE.sigma_s);  // channel mask respected
}

TEST(Brush, ChannelMaskAndSanitiseOnPaint) {
    MaterialVolume v(unitGrid(32), BASE);
    BrushSettings b = baseBrush(BrushMode::Set);
    b.channels = uint8_t(Channel::SigmaT);
    b.falloff = Falloff::Constant;
    b.strength = 1.f;
    b.value.sigma_t = Rgb(0.5f);  // below σs′: σs′ is clamped down to keep σs′ ≤ σt
    stamp(v, b, CENTER);
    EXPECT_EQ(v.at(AT_CENTER).sigma_t, Rgb(0.5f));
    EXPECT_EQ(v.at(AT_CENTER).sigma_s, Rgb(0.5f));
    EXPECT_EQ(v.at(AT_CENTER).g, BASE.g);
}

TEST(Brush, InvariantUnderRandomOps) {
    // 1000 random stamps/strokes/fills of every mode: σt ∈ [0, SIGMA_MAX], 0 ≤ σs′ ≤ σt,
    // |g| ≤ 0.99 everywhere, never NaN.
    MaterialVolume v(unitGrid(32), BASE);
    v.setInsideMask(ballMask(32, 14.f));
    Pcg32 rng(42);
    for (int op = 0; op < 1000; ++op) {
        BrushSettings b;
        b.mode = BrushMode(rng.uniformBelow(6));
        b.falloff = Falloff(rng.uniformBelow(4));
        b.channels = ChannelMask(1 + rng.uniformBelow(7));
        b.radius = 0.5f + 8.f * rng.uniform();
        b.strength = rng.uniform();
        const float scale = b.mode == BrushMode::Multiply ? 3.f : 10.f;
        for (int c = 0; c < 3; ++c) {
            b.value.sigma_t[c] = scale * rng.uniform();
            b.value.sigma_s[c] = b.mode == BrushMode::Set ? b.value.sigma_t[c] * rng.uniform()
                                                          : scale * rng.uniform();
            b.value.g[c] = b.mode == BrushMode::Multiply ? 3.f * rng.uniform()
                           : b.mode == BrushMode::Set    ? 1.98f * rng.uniform() - 0.99f
                                                         : 1.98f * rng.uniform();
        }
        const Point3f p(32.f * rng.uniform(), 32.f * rng.uniform(), 32.f * rng.uniform());
        if (op % 50 == 49)
            fillInterior(v, {Rgb(rng.uniform()), Rgb(0.5f * rng.uniform()), Rgb(0.f)},
                         ChannelMask(1 + rng.uniformBelow(7)));
        else if (op % 3 == 0)
            paintStroke(v, b, {p, p + Vector3f(4.f * rng.uniform(), 3.f, -2.f)});
        else
            stamp(v, b, p);
    }
    const int n = 32;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const MaterialSample s = v.at({x, y, z});
                for (int c = 0; c < 3; ++c) {
                    ASSERT_TRUE(s.sigma_t[c] >= 0.f && s.sigma_t[c] <= SIGMA_MAX);
                    ASSERT_TRUE(s.sigma_s[c] >= 0.f && s.sigma_s[c] <= s.sigma_t[c]);
                    ASSERT_TRUE(std::abs(s.g[c]) <= G_MAX);
                }
            }
}

TEST(Brush, DirtyBricksAreExactlyTheTouchedOnes) {
    const int n = 32;
    MaterialVolume v(unitGrid(n), BASE);
    v.setInsideMask(ballMask(n, 13.f));
    Pcg32 rng(7);
    for (int trial = 0; trial < 50; ++trial) {
        v.takeDirtyBricks();
        BrushSettings b = baseBrush(BrushMode(rng.uniformBelow(6)));
        b.radius = 0.3f + 7.f * rng.uniform();
        b.strength = 0.1f + 0.9f * rng.uniform();
        const Point3f p(34.f * rng.uniform() - 1.f, 34.f * rng.uniform() - 1.f,
                        34.f * rng.uniform() - 1.f);
        History h;
        h.beginStroke(v);
        const size_t touched = stamp(v, b, p, &h);
        // Brute force: bricks holding an inside voxel whose centre is strictly within r.
        std::set<int> want;
        size_t count = 0;
        for (int z = 0; z < n; ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const glm::dvec3 d = glm::dvec3(x + 0.5, y + 0.5, z + 0.5) - glm::dvec3(p);
                    if (v.isInside({x, y, z}) && glm::dot(d, d) < double(b.radius) * b.radius) {
                        want.insert(v.brickIndexOf({x, y, z}));
                        ++count;
                    }
                }
        const std::vector<int> dirty = v.takeDirtyBricks();
        EXPECT_EQ(std::set<int>(dirty.begin(), dirty.end()), want);
        EXPECT_EQ(touched, count);
        h.endStroke(v);
        // The history stored exactly those bricks: one 18 KiB copy each (undo swaps it).
        const size_t brickBytes =
            size_t(MaterialVolume::BRICK_VOXELS) * MaterialVolume::COMPONENTS * 4;
        if (want.empty()) {
            EXPECT_EQ(h.undoCount(), 0u);
        } else {
            EXPECT_GE(h.bytesUsed(), brickBytes * want.size());
            EXPECT_LE(h.bytesUsed(), brickBytes * want.size() + 4 * want.size() + 1024);
        }
    }
}

TEST(Brush, StrokeSpacing) {
    BrushSettings b = baseBrush(BrushMode::Add);
    b.radius = 4.f;
    b.spacing = 0.25f;  // 1 mm
    const auto s = strokeStamps({Point3f(0.f), Point3f(10.f, 0.f, 0.f)}, b);
    ASSERT_EQ(s.size(), 11u);
    for (size_t i = 0; i < s.size(); ++i)
        EXPECT_NEAR(s[i].x, float(i), 1e-5f);
    // Spacing continues across polyline corners: arc lengths 0, 1, 2, 3.
    const auto c =
        strokeStamps({Point3f(0.f), Point3f(1.5f, 0.f, 0.f), Point3f(1.5f, 1.5f, 0.f)}, b);
    ASSERT_EQ(c.size(), 4u);
    EXPECT_NEAR(c[2].x, 1.5f, 1e-5f);
    EXPECT_NEAR(c[2].y, 0.5f, 1e-5f);
    EXPECT_NEAR(c[3].y, 1.5f, 1e-5f);
    EXPECT_EQ(strokeStamps({Point3f(3.f)}, b).size(), 1u);
}

TEST(Brush, InvalidParametersThrow) {
    MaterialVolume v(unitGrid(16), BASE);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    auto bad = [&](auto edit) {
        BrushSettings b = baseBrush(BrushMode::Set);
        edit(b);
        EXPECT_THROW(stamp(v, b, Point3f(8.f)), ValueError);
        EXPECT_THROW(validateBrush(b), ValueError);
    };
    bad([&](BrushSettings& b) { b.radius = nan; });
    bad([&](BrushSettings& b) { b.radius = -1.f; });
    bad([&](BrushSettings& b) { b.radius = 0.f; });
    bad([&](BrushSettings& b) { b.radius = 1e9f; });
    bad([&](BrushSettings& b) { b.strength = 1.5f; });
    bad([&](BrushSettings& b) { b.strength = nan; });
    bad([&](BrushSettings& b) { b.spacing = 0.f; });
    bad([&](BrushSettings& b) { b.spacing = inf; });
    bad([&](BrushSettings& b) { b.channels = 0; });
    bad([&](BrushSettings& b) { b.channels = 8; });
    bad([&](BrushSettings& b) { b.mode = BrushMode(17); });
    bad([&](BrushSettings& b) { b.falloff = Falloff(9); });
    bad([&](BrushSettings& b) { b.value.sigma_t.g = inf; });
    bad([&](BrushSettings& b) { b.value.g.r = nan; });
    bad([&](BrushSettings& b) { b.value.sigma_t.r = -1.f; });
    bad([&](BrushSettings& b) { b.value.g.b = 1.5f; });
    bad([&](BrushSettings& b) { b.value.sigma_s = Rgb(9.f); });  // σs′ > σt with Set
    bad([&](BrushSettings& b) {
        b.mode = BrushMode::Multiply;
        b.value.sigma_t = Rgb(-2.f);
    });
    bad([&](BrushSettings& b) {
        b.mode = BrushMode::Add;
        b.value.sigma_s = Rgb(-0.1f);
    });
    const BrushSettings ok = baseBrush(BrushMode::Set);
    EXPECT_THROW(stamp(v, ok, Point3f(nan, 0.f, 0.f)), ValueError);
    EXPECT_THROW(strokeStamps({}, ok), ValueError);
    EXPECT_THROW(strokeStamps({Point3f(0.f), Point3f(inf)}, ok), ValueError);
    EXPECT_THROW(strokeStamps({Point3f(0.f), Point3f(1e9f, 0.f, 0.f)}, ok), ValueError);
    EXPECT_THROW(fillInterior(v, {Rgb(nan), Rgb(0.f), Rgb(0.f)}), ValueError);
    EXPECT_THROW(fillInterior(v, {Rgb(1.f), Rgb(0.f), Rgb(2.f)}), ValueError);
    EXPECT_THROW(fillInterior(v, {Rgb(1.f), Rgb(0.f), Rgb(0.f)}, 0), ValueError);
    MaterialVolume empty;
    EXPECT_THROW(stamp(empty, ok, Point3f(0.f)), ValueError);
    // Nothing was modified by the rejected calls.
    EXPECT_TRUE(v.isHomogeneous());
    EXPECT_EQ(v.at({8, 8, 8}), sanitize(BASE));
}

TEST(Brush, FillInteriorRespectsMaskAndChannels) {
    MaterialVolume v(unitGrid(16), BASE);
    v.setInsideMask(ballMask(16, 6.f));
    fillInterior(v, {Rgb(9.f), Rgb(20.f), Rgb(0.5f)},
                 uint8_t(Channel::SigmaT) | uint8_t(Channel::G));
    EXPECT_EQ(v.at({8, 8, 8}).sigma_t, Rgb(9.f));
    EXPECT_EQ(v.at({8, 8, 8}).sigma_s, BASE.sigma_s);
    EXPECT_EQ(v.at({8, 8, 8}).g, Rgb(0.5f));
    EXPECT_EQ(v.at({0, 0, 0}), MaterialSample{});
    EXPECT_TRUE(v.isHomogeneous());
}
