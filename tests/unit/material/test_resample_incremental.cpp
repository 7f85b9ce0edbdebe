// SPDX-License-Identifier: MIT
/// @file
/// @brief Incremental resampling (updateCoarseMaterial) against full resampling, and the fast
/// full resample against the original dense implementation, both bit for bit.
#include <lucent/core/Error.h>
#include <lucent/material/BoundarySkin.h>
#include <lucent/material/Brush.h>
#include <lucent/material/Resample.h>

#include "TestUtil.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>

using namespace lucent;
using lucent::test::unitGrid;

namespace {

/// Bit patterns must match (NaN-safe, distinguishes ±0).
void expectBitEqual(const CoarseMaterial& a, const CoarseMaterial& b) {
    ASSERT_EQ(a.spec, b.spec);
    EXPECT_EQ(a.homogeneous, b.homogeneous);
    const size_t bytes = a.spec.voxelCount() * sizeof(float);
    auto same = [&](const std::vector<float>& x, const std::vector<float>& y) {
        return x.size() == y.size() && std::memcmp(x.data(), y.data(), bytes) == 0;
    };
    EXPECT_TRUE(same(a.insideFraction, b.insideFraction));
    for (int c = 0; c < 3; ++c) {
        SCOPED_TRACE(c);
        EXPECT_TRUE(same(a.sigma_t[c], b.sigma_t[c]));
        EXPECT_TRUE(same(a.sigma_s[c], b.sigma_s[c]));
        EXPECT_TRUE(same(a.g[c], b.g[c]));
    }
}

double logMeanT(const std::vector<double>& tau, const std::vector<double>& w) {
    double tmin = std::numeric_limits<double>::infinity();
    for (double t : tau)
        tmin = std::min(tmin, t);
    double num = 0.0, den = 0.0;
    for (size_t i = 0; i < tau.size(); ++i) {
        num += w[i] * std::exp(-(tau[i] - tmin));
        den += w[i];
    }
    return -tmin + std::log(num / den);
}

/// The original (pre-optimisation) implementation on dense arrays, kept as the reference the
/// fast resampler must reproduce exactly.
CoarseMaterial denseReference(const MaterialVolume& volume, int resolution) {
    const int n = volume.resolution();
    const GridSpec& fs = volume.spec();
    CoarseMaterial out;
    out.spec.origin = fs.origin;
    out.spec.resolution = resolution;
    out.spec.voxelSize = fs.voxelSize * float(n) / float(resolution);
    const size_t cells = out.spec.voxelCount();
    for (int c = 0; c < 3; ++c) {
        out.sigma_t[c].assign(cells, 0.f);
        out.sigma_s[c].assign(cells, 0.f);
        out.g[c].assign(cells, 0.f);
    }
    out.insideFraction.assign(cells, 0.f);
    struct Ov {
        int fine;
        double length;
    };
    const double ratio = double(n) / double(resolution);
    std::vector<std::vector<Ov>> lists(static_cast<size_t>(resolution));
    for (int I = 0; I < resolution; ++I) {
        const double a = I * ratio, b = (I + 1) * ratio;
        for (int i = int(std::floor(a)); i < n && double(i) < b; ++i) {
            const double len = std::min(double(i + 1), b) - std::max(double(i), a);
            if (len > 1e-12)
                lists[size_t(I)].push_back({i, len});
        }
    }
    // The material: the painted values inside the mask, the boundary skin's next to it
    // (boundarySkin, written independently of the resampler's per-voxel reads).
    std::vector<uint8_t> inside = volume.insideMask();
    std::vector<float> st[3], ss[3], gg[3];
    for (int c = 0; c < 3; ++c) {
        st[c] = volume.denseComponent(MaterialVolume::component(Channel::SigmaT, c));
        ss[c] = volume.denseComponent(MaterialVolume::component(Channel::SigmaS, c));
        gg[c] = volume.denseComponent(MaterialVolume::component(Channel::G, c));
        for (size_t i = 0; i < inside.size(); ++i)
            if (!inside[i])
                st[c][i] = ss[c][i] = gg[c][i] = 0.f;
    }
    for (const SkinVoxel& s : boundarySkin(volume)) {
        inside[s.index] = 1;
        for (int c = 0; c < 3; ++c) {
            st[c][s.index] = s.value.sigma_t[c];
            ss[c][s.index] = s.value.sigma_s[c];
            gg[c][s.index] = s.value.g[c];
        }
    }
    const double h = fs.voxelSize, H = ratio * h, cellVolume = ratio * ratio * ratio;
    std::vector<double> tau, w;
    for (int K = 0; K < resolution; ++K)
        for (int J = 0; J < resolution; ++J)
            for (int I = 0; I < resolution; ++I) {
                const auto &LX = lists[size_t(I)], &LY = lists[size_t(J)], &LZ = lists[size_t(K)];
                const size_t ci = out.spec.linearIndex({I, J, K});
                double insideVol = 0.0, sumSt[3] = {}, sumSs[3] = {}, sumSsG[3] = {};
                for (const Ov& z : LZ)
                    for (const Ov& y : LY)
                        for (const Ov& x : LX) {
                            const size_t fi = fs.linearIndex({x.fine, y.fine, z.fine});
                            if (!inside[fi])
                                continue;
                            const double wv = x.length * y.length * z.length;
                            insideVol += wv;
                            for (int c = 0; c < 3; ++c) {
                                sumSt[c] += wv * st[c][fi];
                                sumSs[c] += wv * ss[c][fi];
                                sumSsG[c] += wv * ss[c][fi] * gg[c][fi];
                            }
                        }
                out.insideFraction[ci] = float(insideVol / cellVolume);
                for (int c = 0; c < 3; ++c) {
                    double logT[3];
                    for (int axis = 0; axis < 3; ++axis) {
                        const auto& LA = axis == 0 ? LX : axis == 1 ? LY : LZ;
                        const auto& LU = axis == 0 ? LY : LX;
                        const auto& LV = axis == 2 ? LY : LZ;
                        tau.clear();
                        w.clear();
                        for (const Ov& v : LV)
                            for (const Ov& u : LU) {
                                double t = 0.0;
                                for (const Ov& a : LA) {
                                    Coord q;
                                    q[axis] = a.fine;
                                    q[axis == 0 ? 1 : 0] = u.fine;
                                    q[axis == 2 ? 1 : 2] = v.fine;
                                    t += double(st[c][fs.linearIndex(q)]) * a.length;
                                }
                                tau.push_back(t * h);
                                w.push_back(u.length * v.length);
                            }
                        logT[axis] = logMeanT(tau, w);
                    }
                    const double logMean = logMeanT({-logT[0], -logT[1], -logT[2]}, {1., 1., 1.});
                    const double sigmaT = std::max(0.0, -logMean / H);
                    const double albedo = sumSt[c] > 0.0 ? sumSs[c] / sumSt[c] : 0.0;
                    out.sigma_t[c][ci] = float(std::min(sigmaT, double(SIGMA_MAX)));
                    out.sigma_s[c][ci] = std::min(float(albedo * sigmaT), out.sigma_t[c][ci]);
                    out.g[c][ci] = sumSs[c] > 0.0 ? float(sumSsG[c] / sumSs[c]) : 0.f;
                }
            }
    // The reference's homogeneity rule (every cell with material identical).
    out.homogeneous = true;
    bool haveRef = false;
    size_t ref = 0;
    for (size_t i = 0; i < cells; ++i) {
        if (out.insideFraction[i] <= 0.f)
            continue;
        if (!haveRef) {
            ref = i;
            haveRef = true;
            continue;
        }
        bool same = out.insideFraction[i] == out.insideFraction[ref];
        for (int c = 0; c < 3; ++c)
            same = same && out.sigma_t[c][i] == out.sigma_t[c][ref] &&
                   out.sigma_s[c][i] == out.sigma_s[c][ref] && out.g[c][i] == out.g[c][ref];
        out.homogeneous = out.homogeneous && same;
    }
    return out;
}

/// A ball-shaped inside mask (so coarse cells are partly inside) in an n³ unit grid.
MaterialVolume ballVolume(int n) {
    MaterialVolume v(unitGrid(n), {Rgb(0.4f, 0.8f, 1.2f), Rgb(0.3f, 0.5f, 0.6f), Rgb(0.2f)});
    std::vector<uint8_t> mask(v.spec().voxelCount(), 0);
    const float r = 0.42f * float(n), c = 0.5f * float(n);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const Point3f p = v.spec().cellCenter({x, y, z});
                if (glm::length(p - Point3f(c)) < r)
                    mask[v.spec().linearIndex({x, y, z})] = 1;
            }
    v.setInsideMask(mask);
    (void)v.takeDirtyBricks();
    return v;
}

/// A random stroke of `stamps` points with random mode/value.
void randomStroke(MaterialVolume& v, std::mt19937& rng) {
    const float n = float(v.resolution());
    std::uniform_real_distribution<float> pos(0.1f * n, 0.9f * n), unit(0.f, 1.f);
    BrushSettings brush;
    brush.radius = 2.f + 4.f * unit(rng);  // mm: 2–6 voxels
    brush.mode = unit(rng) < 0.7f ? BrushMode::Set : BrushMode::Multiply;
    brush.strength = 0.3f + 0.7f * unit(rng);
    if (brush.mode == BrushMode::Set) {
        const Rgb st(5.f * unit(rng), 5.f * unit(rng), 5.f * unit(rng));  // mm⁻¹
        brush.value = {st, st * Rgb(unit(rng), unit(rng), unit(rng)), Rgb(1.8f * unit(rng) - 0.9f)};
    } else
        brush.value = {Rgb(0.1f + 3.f * unit(rng)), Rgb(0.1f + 3.f * unit(rng)), Rgb(1.f)};
    const Point3f a(pos(rng), pos(rng), pos(rng)), b(pos(rng), pos(rng), pos(rng));
    paintStroke(v, brush, {a, b});
}

}  // namespace

TEST(ResampleIncremental, FullResampleMatchesDenseReferenceBitExactly) {
    std::mt19937 rng(7);
    MaterialVolume v = ballVolume(40);  // 40 = 5 bricks per axis: exact brick layout
    for (int s = 0; s < 6; ++s)
        randomStroke(v, rng);
    for (int res : {40, 16, 13, 7, 1}) {  // 13, 7: fractional overlaps
        SCOPED_TRACE(res);
        expectBitEqual(resampleForPropagation(v, res), denseReference(v, res));
    }
    // A grid that is not a multiple of the brick size (partial bricks).
    MaterialVolume w = ballVolume(21);
    randomStroke(w, rng);
    expectBitEqual(resampleForPropagation(w, 6), denseReference(w, 6));
}

TEST(ResampleIncremental, UpdateAfterRandomStrokesEqualsFullResample) {
    std::mt19937 rng(42);
    for (auto [n, res] : {std::pair{64, 16}, std::pair{64, 24}, std::pair{36, 11}}) {
        SCOPED_TRACE(testing::Message() << n << " -> " << res);
        MaterialVolume v = ballVolume(n);
        CoarseMaterial coarse = resampleForPropagation(v, res);
        const CoarseMaterial before = coarse;
        for (int stroke = 0; stroke < 8; ++stroke) {
            randomStroke(v, rng);
            const std::vector<int> dirty = v.takeDirtyBricks();
            ASSERT_FALSE(dirty.empty());
            const size_t updated = updateCoarseMaterial(coarse, v, dirty);
            EXPECT_GT(updated, 0u);
            EXPECT_LT(updated, coarse.spec.voxelCount());  // a stroke never covers the ball
            expectBitEqual(coarse, resampleForPropagation(v, res));
        }
        // The strokes did change the coarse grid (the test is not vacuous).
        EXPECT_NE(std::memcmp(before.sigma_t[0].data(), coarse.sigma_t[0].data(),
                              coarse.sigma_t[0].size() * sizeof(float)),
                  0);
    }
}

TEST(ResampleIncremental, MaskChangeAndNoOpUpdates) {
    MaterialVolume v = ballVolume(32);
    CoarseMaterial coarse = resampleForPropagation(v, 8);
    EXPECT_EQ(updateCoarseMaterial(coarse, v, {}), 0u);
    // Shrinking the mask marks every brick dirty; the update then equals a full resample.
    std::vector<uint8_t> mask = v.insideMask();
    for (size_t i = 0; i < mask.size(); i += 3)
        mask[i] = 0;
    v.setInsideMask(mask);
    updateCoarseMaterial(coarse, v, v.takeDirtyBricks());
    expectBitEqual(coarse, resampleForPropagation(v, 8));
    // A single dirty brick updates only the coarse cells overlapping its 8³ voxels: 2³ here
    // (brick 0, in the grid's corner, holds no inside voxel, so no skin value reads it).
    EXPECT_EQ(updateCoarseMaterial(coarse, v, {0}), 8u);
    // A brick holding inside voxels next to masked-out ones (the mask's holes) also updates the
    // cells over the voxels around it, whose skin values read its voxels: voxels 7–16 per axis,
    // cells 1–4, 4³.
    ASSERT_TRUE(v.isInside({12, 12, 13}));
    ASSERT_FALSE(v.isInside({12, 12, 12}));
    EXPECT_EQ(updateCoarseMaterial(coarse, v, {v.brickIndexOf({8, 8, 8})}), 64u);
}

TEST(ResampleIncremental, RejectsMismatchedInput) {
    MaterialVolume v = ballVolume(32);
    CoarseMaterial coarse = resampleForPropagation(v, 8);
    EXPECT_THROW(updateCoarseMaterial(coarse, v, {v.brickCount()}), ValueError);
    EXPECT_THROW(updateCoarseMaterial(coarse, v, {-1}), ValueError);
    MaterialVolume other = ballVolume(16);
    EXPECT_THROW(updateCoarseMaterial(coarse, other, {0}), ValueError);
    CoarseMaterial broken = coarse;
    broken.g[2].pop_back();
    EXPECT_THROW(updateCoarseMaterial(broken, v, {0}), ValueError);
}

TEST(ResampleIncremental, StrokeUpdateIsMuchCheaperThanFullResample) {
    // 128³ → 32³, the live-preview configuration; timings are printed for docs/benchmarks.md.
    std::mt19937 rng(3);
    MaterialVolume v = ballVolume(128);
    for (int s = 0; s < 20; ++s)
        randomStroke(v, rng);
    (void)v.takeDirtyBricks();
    using Clock = std::chrono::steady_clock;
    auto t0 = Clock::now();
    CoarseMaterial coarse = resampleForPropagation(v, 32);
    const double fullMs = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    BrushSettings brush;
    brush.radius = 8.f;
    brush.value = {Rgb(3.f), Rgb(1.f), Rgb(0.5f)};
    paintStroke(v, brush, {Point3f(40.f, 64.f, 64.f), Point3f(80.f, 64.f, 64.f)});
    const std::vector<int> dirty = v.takeDirtyBricks();
    t0 = Clock::now();
    const size_t cells = updateCoarseMaterial(coarse, v, dirty);
    const double incMs = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    std::printf(
        "[resample 128^3->32^3] full %.1f ms; 40 mm stroke: %zu bricks, %zu cells, "
        "incremental %.2f ms\n",
        fullMs, dirty.size(), cells, incMs);
    expectBitEqual(coarse, resampleForPropagation(v, 32));
    // The stroke touches a small fraction of the 32³ cells, so the update does that much work.
    EXPECT_LT(cells, coarse.spec.voxelCount() / 8);
}
