// SPDX-License-Identifier: MIT
/// @file
/// @brief Validation of the path tracer's transport kernels against closed forms. Every
/// tolerance is a multiple of the Monte Carlo standard error measured from the samples
/// (5σ: a false failure about once in 1.7 million runs) plus any stated quadrature error.

#include "TestScenes.h"

#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/core/Sampling.h>
#include <lucent/core/SphericalHarmonics.h>
#include <lucent/reference/Transport.h>

#include <gtest/gtest.h>

using namespace lucent;
using namespace lucent::reference;
using namespace lucent::test;

namespace {

constexpr double Z = 5.0;  // tolerance in standard errors

GridMedium::Options opts(MajorantMode mode, bool fastPath = true) {
    GridMedium::Options o;
    o.majorant = mode;
    o.homogeneousFastPath = fastPath;
    return o;
}

/// Heterogeneous pure absorber on [0,16]³ (1 mm voxels): σt depends on i and k per channel.
MediumCoefficients absorber(int i, int, int k) {
    MediumCoefficients m;
    m.sigma_t = Rgb(0.05f * float(1 + i % 4), 0.02f * float(1 + (i + k) % 5), i < 8 ? 0.f : 0.3f);
    m.sigma_a = m.sigma_t;
    return m;
}

/// Optical depth of a straight segment by midpoint quadrature (error ≤ number of voxel faces
/// crossed × step × max σt ≈ 48 × 1.6e-5 × 0.3 ≈ 2e-4 in τ for 10⁶ steps over 16√3 mm).
double opticalDepth(const GridMedium& m, const Point3f& a, const Point3f& b, int ch) {
    const int steps = 1000000;
    const double len = glm::length(b - a);
    double tau = 0;
    for (int s = 0; s < steps; ++s) {
        const float t = (float(s) + 0.5f) / float(steps);
        tau += m.sigmaT(a + (b - a) * t, ch);
    }
    return tau * len / steps;
}

}  // namespace

TEST(Fresnel, ClosedFormValues) {
    // Normal incidence: F = ((η − 1)/(η + 1))² (Born & Wolf).
    EXPECT_NEAR(fresnelDielectric(1.f, 1.5f), 0.04f, 1e-6f);
    EXPECT_NEAR(fresnelDielectric(1.f, 1.f / 1.5f), 0.04f, 1e-6f);
    EXPECT_FLOAT_EQ(fresnelDielectric(0.7f, 1.f), 0.f);  // index matched: no reflection
    // Total internal reflection beyond the critical angle sin θc = 1/η.
    const float cosCrit = std::sqrt(1.f - 1.f / (1.3f * 1.3f));
    EXPECT_FLOAT_EQ(fresnelDielectric(cosCrit - 1e-3f, 1.f / 1.3f), 1.f);
    EXPECT_LT(fresnelDielectric(cosCrit + 1e-2f, 1.f / 1.3f), 1.f);
    EXPECT_NEAR(fresnelDielectric(0.f, 1.5f), 1.f, 1e-6f);  // grazing
}

TEST(GridMedium, RejectsInvalidCoefficients) {
    GridSpec spec;
    spec.resolution = 2;
    std::vector<MediumCoefficients> v(8, grey(1.f, 0.5f));
    v[3].sigma_s = Rgb(2.f);  // σs > σt
    EXPECT_THROW(GridMedium(spec, v, {}), ValueError);
    v[3] = grey(-1.f, 0.f);
    EXPECT_THROW(GridMedium(spec, v, {}), ValueError);
    v.pop_back();
    EXPECT_THROW(GridMedium(spec, v, {}), ValueError);
}

TEST(Transport, BeerLambertRatioTracking) {
    // Ratio tracking is an unbiased estimator of T = exp(−τ) for a pure absorber; checked
    // along an axis (τ exact: sum of voxel σ × 1 mm) and a diagonal (τ by quadrature), with
    // brick and global majorants, in every channel.
    for (MajorantMode mode : {MajorantMode::Bricks, MajorantMode::Global}) {
        const GridMedium m = gridFrom({0, 0, 0}, 1.f, 16, absorber, opts(mode));
        struct Ray {
            Point3f a, b;
        };
        for (const Ray& ray : {Ray{{0, 8.5f, 8.5f}, {16, 8.5f, 8.5f}},
                               Ray{{0.3f, 0.2f, 0.1f}, {15.9f, 15.7f, 15.8f}}}) {
            const Vector3f d = glm::normalize(ray.b - ray.a);
            const float len = glm::length(ray.b - ray.a);
            for (int ch = 0; ch < 3; ++ch) {
                const double exact = std::exp(-opticalDepth(m, ray.a, ray.b, ch));
                Pcg32 rng(17 + uint64_t(ch));
                MeanSe est;
                for (int i = 0; i < 20000; ++i)
                    est.add(estimateTransmittance(m, ray.a, d, len, ch, rng));
                // 5 standard errors + quadrature error of exp(−τ): T·2e-4.
                EXPECT_NEAR(est.mean(), exact, Z * est.se() + 2e-4 * exact + 1e-6)
                    << "mode " << int(mode) << " channel " << ch;
            }
        }
    }
}

TEST(Transport, BeerLambertDeltaTrackingEscape) {
    // A walk in a pure absorber ends at its first collision (albedo 0), so the fraction of
    // walks that cross the box is a binomial estimate of T = exp(−τ): σ = √(T(1−T)/N).
    const GridMedium m = gridFrom({0, 0, 0}, 1.f, 16, absorber, opts(MajorantMode::Bricks));
    const VolumeScene scene(boxMesh({0, 0, 0}, {16, 16, 16}), m, {});
    TransportOptions to;
    to.boundary = BoundaryModel::Matched;
    const int n = 40000;
    for (int ch = 0; ch < 3; ++ch) {
        const Point3f a(1e-4f, 8.5f, 8.5f), b(16.f, 8.5f, 8.5f);
        const double t = std::exp(-opticalDepth(m, a, b, ch));
        Pcg32 rng(99 + uint64_t(ch));
        int escaped = 0;
        for (int i = 0; i < n; ++i) {
            const WalkResult w = walkMedium(scene, a, {1, 0, 0}, ch, rng, to);
            if (w.escaped) {
                ++escaped;
                EXPECT_EQ(w.scatterCount, 0);
                EXPECT_NEAR(w.position.x, 16.f, 1e-3f);
            }
        }
        const double sigma = std::sqrt(t * (1 - t) / n);
        EXPECT_NEAR(double(escaped) / n, t, Z * sigma + 2e-4 * t) << "channel " << ch;
    }
}

TEST(Transport, WhiteFurnaceAllFluxLeaves) {
    // Albedo 1 everywhere (σs = σt, heterogeneous, anisotropic in places): nothing is absorbed,
    // so every walk that enters must leave with weight exactly 1, for the matched and the
    // dielectric boundary (Fresnel only redirects flux). Roulette never triggers at weight 1.
    const auto white = [](int i, int j, int k) {
        const float s = 0.3f + 0.4f * float((i * 7 + j * 3 + k * 5) % 6);
        return grey(s, s, (i + j) % 3 == 0 ? 0.6f : -0.2f);
    };
    const GridMedium m = gridFrom({-6, -6, -6}, 0.75f, 16, white, opts(MajorantMode::Bricks));
    const VolumeScene scene(boxMesh({-5, -5, -5}, {5, 5, 5}), m, {});
    for (BoundaryModel bm : {BoundaryModel::Matched, BoundaryModel::Dielectric}) {
        TransportOptions to;
        to.boundary = bm;
        to.eta = 1.4f;
        Pcg32 rng(5);
        const int n = 4000;
        double flux = 0;
        int totalScatter = 0;
        for (int i = 0; i < n; ++i) {
            // Enter through the top face at a random point, cosine-distributed inward.
            const Point3f p(-5.f + 10.f * rng.uniform(), 5.f - 1e-4f, -5.f + 10.f * rng.uniform());
            const Vector3f local = sampleCosineHemisphere({rng.uniform(), rng.uniform()});
            const WalkResult w = walkMedium(scene, p, {local.x, -local.z, local.y}, i % 3, rng, to);
            if (w.escaped)
                flux += w.weight;
            totalScatter += w.scatterCount;
        }
        // Exact conservation: all n units of flux leave (no statistical tolerance needed).
        EXPECT_DOUBLE_EQ(flux, double(n)) << "boundary " << int(bm);
        EXPECT_GT(totalScatter, n);  // the walks really scattered
    }
}

TEST(Transport, SingleScatteringThinSlab) {
    // Slab 0 ≤ z ≤ d, lit at normal incidence from below, isotropic phase, index matched.
    // Single-scattered reflectance and transmittance (flux fractions), with τ = σt·d, α = σs/σt:
    //   R1 = (α/2) ∫₀¹ ∫₀^τ e^{−s(1 + 1/μ)} ds dμ
    //   T1 = (α/2) ∫₀¹ ∫₀^τ e^{−s} e^{−(τ − s)/μ} ds dμ
    // (first-order solution of the RTE for a plane-parallel slab, Chandrasekhar 1960 §1.4 /
    // Ishimaru 1978 Eq. 9-22), evaluated by 2-D midpoint quadrature (error < 1e-6).
    const float sigmaT = 1.f, sigmaS = 0.5f, d = 1.f;
    const double tau = sigmaT * d, alpha = sigmaS / sigmaT;
    double r1 = 0, t1 = 0;
    const int q = 1500;
    for (int a = 0; a < q; ++a) {
        const double mu = (a + 0.5) / q;
        for (int b = 0; b < q; ++b) {
            const double s = (b + 0.5) / q * tau;
            r1 += std::exp(-s * (1 + 1 / mu));
            t1 += std::exp(-s) * std::exp(-(tau - s) / mu);
        }
    }
    r1 *= alpha / 2 * tau / (double(q) * q);
    t1 *= alpha / 2 * tau / (double(q) * q);

    GridSpec spec;
    spec.origin = Point3f(-100.f);
    spec.voxelSize = 12.5f;
    spec.resolution = 16;
    for (bool fast : {true, false}) {
        const GridMedium m =
            GridMedium::uniform(spec, grey(sigmaT, sigmaS), opts(MajorantMode::Bricks, fast));
        // 200 mm wide: a single-scattered path reaching the side travels ≥ 100 mm in the slab
        // (attenuation e^{−100}), so the slab is infinite for this estimate.
        const VolumeScene scene(boxMesh({-100, -100, 0}, {100, 100, d}), m, {});
        TransportOptions to;
        to.boundary = BoundaryModel::Matched;
        to.russianRoulette = false;
        Pcg32 rng(fast ? 11 : 12);
        MeanSe r, t;
        for (int i = 0; i < 100000; ++i) {
            const WalkResult w = walkMedium(scene, {0, 0, 1e-4f}, {0, 0, 1}, 0, rng, to);
            const bool single = w.escaped && w.scatterCount == 1;
            r.add(single && w.position.z < 0.5f * d ? w.weight : 0.0);
            t.add(single && w.position.z > 0.5f * d ? w.weight : 0.0);
        }
        EXPECT_NEAR(r.mean(), r1, Z * r.se() + 1e-6) << "fast path " << fast;
        EXPECT_NEAR(t.mean(), t1, Z * t.se() + 1e-6) << "fast path " << fast;
    }
}

TEST(Transport, ReciprocitySwapLightAndCamera) {
    // Symmetric (HG) phase function: the scattered fluence at B from a unit point source at A
    // equals the fluence at A from the source at B (Helmholtz reciprocity of the RTE Green's
    // function), for the index-matched boundary and for the exact dielectric one (a box: light
    // entering near an edge is totally reflected by the side faces). Asymmetric placement,
    // heterogeneous medium.
    const GridMedium m = gridFrom({0, 0, 0}, 0.625f, 16, lumpy, opts(MajorantMode::Bricks));
    const TriangleMesh box = boxMesh({0, 0, 0}, {10, 10, 10});
    const Point3f a(-4.f, 3.f, 5.f), b(13.f, 8.f, 2.f);
    Light la;
    la.type = Light::Type::Point;
    la.position = a;
    la.intensity = Rgb(1.f);
    Light lb = la;
    lb.position = b;
    const VolumeScene lightAtA(box, m, {la}), lightAtB(box, m, {lb});
    for (BoundaryModel bm : {BoundaryModel::Matched, BoundaryModel::Dielectric}) {
        TransportOptions to;
        to.boundary = bm;
        to.eta = 1.3f;
        const MeanSe atB = fluenceAt(lightAtA, b, {5, 5, 5}, 8.67f, 300000, 1, to);
        const MeanSe atA = fluenceAt(lightAtB, a, {5, 5, 5}, 8.67f, 300000, 2, to);
        ASSERT_GT(atB.mean(), 0.0);
        EXPECT_NEAR(atB.mean(), atA.mean(), Z * std::hypot(atA.se(), atB.se()))
            << boundaryModelName(bm);
    }
}

TEST(Transport, ErrorFallsAsInverseSqrtN) {
    // RMS error of an N-sample mean of ratio-tracking estimates, over M independent runs,
    // scales as 1/√N: RMSE(N)/RMSE(4N) = 2. With M = 400 runs the RMSE² of each has a relative
    // standard deviation ≈ √(2/M) ≈ 0.071 (Gaussian means), so the ratio of RMSEs has a
    // relative standard deviation ≈ √(2·(0.071/2)²) ≈ 0.05: accept 2 ± 5 × 0.05 × 2.
    const GridMedium m = gridFrom({0, 0, 0}, 1.f, 16, absorber, opts(MajorantMode::Bricks));
    const Point3f a(0.3f, 0.2f, 0.1f), b(15.9f, 15.7f, 15.8f);
    const Vector3f d = glm::normalize(b - a);
    const float len = glm::length(b - a);
    const double exact = std::exp(-opticalDepth(m, a, b, 1));
    const auto rmse = [&](int n, uint64_t seed) {
        Pcg32 rng(seed);
        double se = 0;
        const int runs = 400;
        for (int r = 0; r < runs; ++r) {
            double s = 0;
            for (int i = 0; i < n; ++i)
                s += estimateTransmittance(m, a, d, len, 1, rng);
            se += (s / n - exact) * (s / n - exact);
        }
        return std::sqrt(se / runs);
    };
    const double e16 = rmse(16, 3), e64 = rmse(64, 4);
    EXPECT_NEAR(e16 / e64, 2.0, 0.5);
}

TEST(Transport, UniformGridEqualsHomogeneousFastPath) {
    // The same uniform medium through the grid machinery (brick DDA, σt lookups, null
    // collisions never happen but segments restart at brick faces) and through the closed-form
    // homogeneous path must give the same radiance within Monte Carlo error.
    GridSpec spec;
    spec.origin = Point3f(-6.f);
    spec.voxelSize = 0.75f;
    spec.resolution = 16;
    const MediumCoefficients value = grey(0.8f, 0.7f, 0.4f);
    const TriangleMesh box = boxMesh({-5, -4, -3}, {5, 4, 3});
    Light sun;
    sun.type = Light::Type::Directional;
    sun.direction = glm::normalize(Vector3f(0.3f, -1.f, 0.2f));
    sun.intensity = Rgb(1.f);
    const VolumeScene homogeneous(
        box, GridMedium::uniform(spec, value, opts(MajorantMode::Global, true)), {sun});
    const VolumeScene gridded(
        box, GridMedium::uniform(spec, value, opts(MajorantMode::Bricks, false)), {sun});
    ASSERT_TRUE(homogeneous.medium().isHomogeneous());
    ASSERT_FALSE(gridded.medium().isHomogeneous());
    for (BoundaryModel bm : {BoundaryModel::Matched, BoundaryModel::Dielectric}) {
        TransportOptions to;
        to.boundary = bm;
        to.eta = 1.3f;
        const MeanSe h = fluenceAt(homogeneous, {0, 0, 12}, {0, 0, 0}, 7.1f, 60000, 7, to);
        const MeanSe g = fluenceAt(gridded, {0, 0, 12}, {0, 0, 0}, 7.1f, 60000, 8, to);
        ASSERT_GT(h.mean(), 0.0);
        EXPECT_NEAR(h.mean(), g.mean(), Z * std::hypot(h.se(), g.se())) << int(bm);
    }
}

TEST(Transport, MajorantBricksChangeTimeNotAnswer) {
    // Mostly empty grid with a dense block and a thin haze: the brick majorants skip the empty
    // bricks and bound the haze tightly, the global majorant (= the block's σt) does not.
    const auto sparse = [](int i, int j, int k) {
        if (i >= 8 && i < 16 && j >= 8 && j < 16 && k >= 8 && k < 16)
            return grey(4.f, 3.6f, 0.2f);
        if (k < 8)
            return grey(0.02f, 0.015f);
        return grey(0.f, 0.f);
    };
    const TriangleMesh box = boxMesh({0, 0, 0}, {32, 32, 32});
    Light sun;
    sun.type = Light::Type::Directional;
    sun.direction = glm::normalize(Vector3f(-0.2f, -1.f, 0.1f));
    sun.intensity = Rgb(1.f);
    const VolumeScene bricks(box, gridFrom({0, 0, 0}, 1.f, 32, sparse, opts(MajorantMode::Bricks)),
                             {sun});
    const VolumeScene global(box, gridFrom({0, 0, 0}, 1.f, 32, sparse, opts(MajorantMode::Global)),
                             {sun});
    EXPECT_GT(bricks.medium().majorantCells(), 1);
    // Auto keeps the bricks here (some bricks are far below the global majorant) and drops
    // them for a uniform grid, where they cannot save a lookup.
    EXPECT_EQ(gridFrom({0, 0, 0}, 1.f, 32, sparse, opts(MajorantMode::Auto)).majorantMode(),
              MajorantMode::Bricks);
    EXPECT_EQ(gridFrom(
                  {0, 0, 0}, 1.f, 32, [](int, int, int) { return grey(1.f, 0.5f); },
                  opts(MajorantMode::Auto))
                  .majorantMode(),
              MajorantMode::Global);
    EXPECT_EQ(global.medium().majorantCells(), 1);
    TransportOptions to;
    to.boundary = BoundaryModel::Matched;
    // Transmittance along random chords: same expectation.
    {
        Pcg32 pick(21), r1(22), r2(23);
        MeanSe tb, tg;
        TrackingStats sb, sg;
        for (int i = 0; i < 20000; ++i) {
            const Point3f a(32.f * pick.uniform(), 32.f * pick.uniform(), 0.f);
            const Point3f b(32.f * pick.uniform(), 32.f * pick.uniform(), 32.f);
            const Vector3f d = glm::normalize(b - a);
            const float len = glm::length(b - a);
            tb.add(estimateTransmittance(bricks.medium(), a, d, len, 0, r1, &sb));
            tg.add(estimateTransmittance(global.medium(), a, d, len, 0, r2, &sg));
        }
        EXPECT_NEAR(tb.mean(), tg.mean(), Z * std::hypot(tb.se(), tg.se()));
        EXPECT_LT(double(sb.tentativeCollisions), 0.5 * double(sg.tentativeCollisions));
    }
    // Full radiance: same expectation, fewer lookups.
    {
        TrackingStats sb, sg;
        Pcg32 r1(31), r2(32);
        MeanSe lb, lg;
        for (int i = 0; i < 20000; ++i) {
            const Point3f o(4.f + 24.f * float(i % 100) / 100.f, 40.f,
                            4.f + 24.f * float(i / 100) / 200.f);
            lb.add(estimateRadiance(bricks, o, {0, -1, 0}, 0, r1, to, &sb));
            lg.add(estimateRadiance(global, o, {0, -1, 0}, 0, r2, to, &sg));
        }
        ASSERT_GT(lb.mean(), 0.0);
        EXPECT_NEAR(lb.mean(), lg.mean(), Z * std::hypot(lb.se(), lg.se()));
        EXPECT_LT(double(sb.tentativeCollisions), 0.5 * double(sg.tentativeCollisions));
    }
}

TEST(Transport, SphereLightSeenDirectlyAndThroughMatchedMedium) {
    // A camera ray that misses the object sees the sphere light's radiance exactly; through a
    // pure-absorber slab with η = 1 it sees radiance × T (binomial estimate, 5σ).
    Light ball;
    ball.type = Light::Type::Sphere;
    ball.position = {0, 0, -20};
    ball.radius = 3.f;
    ball.intensity = Rgb(2.f, 1.f, 0.5f);
    GridSpec spec;
    spec.origin = Point3f(-8.f);
    spec.voxelSize = 1.f;
    spec.resolution = 16;
    const VolumeScene scene(boxMesh({-5, -5, -1}, {5, 5, 1}),
                            GridMedium::uniform(spec, grey(0.5f, 0.f), {}), {ball});
    TransportOptions to;
    to.boundary = BoundaryModel::Matched;
    Pcg32 rng(3);
    // From (20, 0, 10) toward the light's centre: passes beside the slab (x = 14 at z = 1).
    EXPECT_FLOAT_EQ(
        estimateRadiance(scene, {20, 0, 10}, glm::normalize(Vector3f(-20, 0, -30)), 0, rng, to),
        2.f);
    MeanSe l;
    for (int i = 0; i < 20000; ++i)
        l.add(estimateRadiance(scene, {0, 0, 10}, {0, 0, -1}, 1, rng, to));
    // Delta tracking makes this a binomial estimate of T = exp(−σt·thickness) = e^{−1}.
    EXPECT_NEAR(l.mean(), std::exp(-0.5 * 2.0), Z * l.se());
}

TEST(Transport, SmallSphereLightActsAsPointLight) {
    // A sphere light of radius r and radiance L seen from distance d ≫ r delivers the irradiance
    // of a point light of intensity I = L·πr² (its projected area times L), up to O((r/d)²):
    // here r = 0.4 mm, d ≥ 8 mm → < 0.3 %. Compared through the whole NEE machinery
    // (cone sampling, units, shadow transmittance), 5σ + 0.3 %. The probe's cone of directions
    // (35° about the box centre) excludes the light itself (43° off axis).
    const GridMedium m = gridFrom({0, 0, 0}, 0.625f, 16, lumpy, opts(MajorantMode::Bricks));
    const TriangleMesh box = boxMesh({0, 0, 0}, {10, 10, 10});
    Light ball;
    ball.type = Light::Type::Sphere;
    ball.position = {-8.f, 4.f, 6.f};
    ball.radius = 0.4f;
    ball.intensity = Rgb(10.f);
    Light point;
    point.type = Light::Type::Point;
    point.position = ball.position;
    point.intensity = Rgb(10.f * PI * 0.4f * 0.4f);
    TransportOptions to;
    to.boundary = BoundaryModel::Dielectric;
    to.eta = 1.33f;
    const MeanSe s =
        fluenceAt(VolumeScene(box, m, {ball}), {5, 5, 20}, {5, 5, 5}, 8.67f, 100000, 3, to);
    const MeanSe p =
        fluenceAt(VolumeScene(box, m, {point}), {5, 5, 20}, {5, 5, 5}, 8.67f, 100000, 4, to);
    ASSERT_GT(p.mean(), 0.0);
    EXPECT_NEAR(s.mean(), p.mean(), Z * std::hypot(s.se(), p.se()) + 3e-3 * p.mean());
}

TEST(Transport, SingleScatteredRadianceWithHenyeyGreenstein) {
    // Slab 0 ≤ z ≤ d under a directional light of irradiance E travelling along ωl, seen from
    // above along ωv (index matched). Radiance of exactly one scattering event (maxScatter = 1;
    // NEE at the first collision), with μv = |ωv·z|, μl = |ωl·z|, cos θ = ωl·(−ωv):
    //   L1 = σs·p_HG(cos θ)·E·(1 − exp(−σt d (1/μv + 1/μl))) / (σt (1 + μv/μl))
    // (single-scattering solution of the RTE, Chandrasekhar 1960 §1.4 / Ishimaru 1978
    // Eq. 9-22). Forward- and backward-peaked g distinguish p(cos θ) from p(−cos θ).
    const float sigmaT = 0.8f, sigmaS = 0.6f, d = 1.5f;
    GridSpec spec;
    spec.origin = Point3f(-100.f);
    spec.voxelSize = 12.5f;
    spec.resolution = 16;
    const Vector3f wl = glm::normalize(Vector3f(0.6f, 0.f, -1.f));
    const Vector3f wv = glm::normalize(Vector3f(0.4f, 0.2f, -1.f));
    for (float g : {0.6f, -0.6f}) {
        Light sun;
        sun.type = Light::Type::Directional;
        sun.direction = wl;
        sun.intensity = Rgb(2.f);
        const VolumeScene scene(boxMesh({-100, -100, 0}, {100, 100, d}),
                                GridMedium::uniform(spec, grey(sigmaT, sigmaS, g),
                                                    opts(MajorantMode::Bricks, /*fastPath=*/false)),
                                {sun});
        TransportOptions to;
        to.boundary = BoundaryModel::Matched;
        to.maxScatter = 1;
        const double muV = -wv.z, muL = -wl.z;
        const double expected = sigmaS * hgPhase(g, glm::dot(wl, -wv)) * 2.0 *
                                (1 - std::exp(-sigmaT * d * (1 / muV + 1 / muL))) /
                                (sigmaT * (1 + muV / muL));
        Pcg32 rng(g > 0 ? 41 : 42);
        MeanSe l;
        for (int i = 0; i < 60000; ++i)
            l.add(estimateRadiance(scene, Point3f(0, 0, d) - 10.f * wv, wv, 0, rng, to));
        EXPECT_NEAR(l.mean(), expected, Z * l.se()) << "g = " << g;
    }
}

TEST(Transport, SpectralMisMatchesPerChannelTracking) {
    // Hero-channel spectral MIS and plain per-channel tracking are both unbiased, so on a
    // strongly chromatic heterogeneous medium (σt, albedo and g differ per channel, with some
    // empty voxels) their per-channel fluences must agree within 5 combined standard errors.
    const auto chroma = [](int i, int j, int k) {
        const float s = float((i * 5 + j * 11 + k * 3) % 7);
        MediumCoefficients m;
        if (s == 0.f)
            return m;  // vacuum pockets
        m.sigma_t = Rgb(0.15f * s, 0.3f + 0.1f * s, 1.2f);
        m.sigma_s = m.sigma_t * Rgb(0.95f, 0.7f, 0.4f);
        m.sigma_a = m.sigma_t - m.sigma_s;
        m.g = Rgb(0.5f, 0.f, -0.3f);
        return m;
    };
    const GridMedium m = gridFrom({0, 0, 0}, 0.625f, 16, chroma, opts(MajorantMode::Bricks));
    Light key;
    key.type = Light::Type::Point;
    key.position = {-6.f, 12.f, 4.f};
    key.intensity = Rgb(50.f, 40.f, 30.f);
    Light sun;
    sun.type = Light::Type::Directional;
    sun.direction = glm::normalize(Vector3f(0.3f, 0.2f, -1.f));
    sun.intensity = Rgb(0.2f, 0.3f, 0.4f);
    const VolumeScene scene(boxMesh({0, 0, 0}, {10, 10, 10}), m, {key, sun});
    TransportOptions to;
    to.boundary = BoundaryModel::Dielectric;
    to.eta = 1.4f;
    const Point3f probe(6.f, -9.f, 15.f), centre(5.f, 5.f, 5.f);
    const Vector3f axis = glm::normalize(centre - probe);
    const float cosMax = std::sqrt(1.f - 8.67f * 8.67f / glm::dot(centre - probe, centre - probe));
    const Frame frame(axis);
    const double invPdf = 2.0 * PI * (1.0 - cosMax);  // uniform cone sampling
    const auto direction = [&](Pcg32& rng) {
        const float cosT = 1.f - rng.uniform() * (1.f - cosMax);
        const float sinT = std::sqrt(std::max(0.f, 1.f - cosT * cosT));
        const float phi = 2.f * PI * rng.uniform();
        return glm::normalize(frame.toWorld({sinT * std::cos(phi), sinT * std::sin(phi), cosT}));
    };
    const int n = 60000;
    MeanSe mis[3], single[3];
    Pcg32 r1(51), r2(52);
    for (int i = 0; i < n; ++i) {
        const Rgb v = estimateRadianceRgb(scene, probe, direction(r1), i % 3, r1, to);
        for (int c = 0; c < 3; ++c)
            mis[c].add(invPdf * v[c]);
        const int c = i % 3;
        single[c].add(invPdf * estimateRadiance(scene, probe, direction(r2), c, r2, to));
    }
    for (int c = 0; c < 3; ++c) {
        ASSERT_GT(single[c].mean(), 0.0);
        EXPECT_NEAR(mis[c].mean(), single[c].mean(), Z * std::hypot(mis[c].se(), single[c].se()))
            << "channel " << c;
    }
}

TEST(Transport, SurfaceReflectionAndSubsurfaceOnly) {
    // A camera ray meets a dielectric slab of black absorber (σt = 20 mm⁻¹: nothing comes back
    // out) at cos θ = 0.8 and sees a sphere light in the mirror direction: the expected radiance
    // is F(0.8)·Le (Fresnel, Born & Wolf), a Bernoulli estimate (5σ). --subsurface-only drops
    // exactly this term: every sample is 0.
    Light ball;
    ball.type = Light::Type::Sphere;
    ball.position = Point3f(0, 0, 1) + 20.f * Vector3f(0.6f, 0, 0.8f);
    ball.radius = 2.f;
    ball.intensity = Rgb(3.f, 2.f, 1.f);
    GridSpec spec;
    spec.origin = Point3f(-60.f);
    spec.voxelSize = 7.5f;
    spec.resolution = 16;
    const VolumeScene scene(boxMesh({-50, -50, -1}, {50, 50, 1}),
                            GridMedium::uniform(spec, grey(20.f, 0.f), {}), {ball});
    const Vector3f d(0.6f, 0.f, -0.8f);
    const Point3f o = Point3f(0, 0, 1) - 10.f * d;
    TransportOptions to;
    to.boundary = BoundaryModel::Dielectric;
    to.eta = 1.3f;
    const double f = fresnelDielectric(0.8f, 1.3f);
    Pcg32 rng(61);
    MeanSe scalar, rgb;
    for (int i = 0; i < 20000; ++i) {
        scalar.add(estimateRadiance(scene, o, d, 0, rng, to));
        rgb.add(estimateRadianceRgb(scene, o, d, i % 3, rng, to).g);
    }
    EXPECT_NEAR(scalar.mean(), f * 3.0, Z * scalar.se());
    EXPECT_NEAR(rgb.mean(), f * 2.0, Z * rgb.se());
    to.subsurfaceOnly = true;
    for (int i = 0; i < 1000; ++i) {
        ASSERT_EQ(estimateRadiance(scene, o, d, 0, rng, to), 0.f);
        ASSERT_EQ(estimateRadianceRgb(scene, o, d, i % 3, rng, to), Rgb(0.f));
    }
}

TEST(Transport, SingleScatteringBelowDielectricCarriesRadianceScaling) {
    // Optically thick slab (σt·d = 16) with a smooth dielectric top, directional light and view
    // both along −z. At normal incidence nothing bends, so the straight shadow connection is
    // exact and the single-scattered radiance has the closed form
    //   L1 = T0 · T0/η² · σs·p_HG(−1)·E / (2σt),   T0 = 1 − ((η−1)/(η+1))²,
    // where 1/η² is the radiance scaling of the camera ray leaving the denser medium
    // (L_out = T·L_in/η²; Veach 1997 §5.2). Without it the estimate is η² too bright.
    const float sigmaT = 0.8f, sigmaS = 0.6f, d = 20.f, g = 0.3f;
    GridSpec spec;
    spec.origin = Point3f(-100.f);
    spec.voxelSize = 12.5f;
    spec.resolution = 16;
    Light sun;
    sun.type = Light::Type::Directional;
    sun.direction = Vector3f(0.f, 0.f, -1.f);
    sun.intensity = Rgb(2.f);
    const VolumeScene scene(boxMesh({-100, -100, -d}, {100, 100, 0}),
                            GridMedium::uniform(spec, grey(sigmaT, sigmaS, g),
                                                opts(MajorantMode::Bricks, /*fastPath=*/false)),
                            {sun});
    for (float eta : {1.3f, 1.8f}) {
        TransportOptions to;
        to.boundary = BoundaryModel::Dielectric;
        to.eta = eta;
        to.maxScatter = 1;
        to.subsurfaceOnly = true;
        const double r0 = double(eta - 1) / double(eta + 1);
        const double t0 = 1.0 - r0 * r0;
        const double expected = t0 * t0 / (double(eta) * eta) * sigmaS * hgPhase(g, -1.f) * 2.0 *
                                (1 - std::exp(-2.0 * sigmaT * d)) / (2.0 * sigmaT);
        Pcg32 rng(eta > 1.5f ? 51 : 52);
        MeanSe l;
        for (int i = 0; i < 40000; ++i)
            l.add(estimateRadiance(scene, Point3f(0.f, 0.f, 10.f), Vector3f(0.f, 0.f, -1.f), 0, rng,
                                   to));
        EXPECT_NEAR(l.mean(), expected, Z * l.se()) << "eta = " << eta;
    }
}
