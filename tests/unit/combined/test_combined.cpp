// SPDX-License-Identifier: MIT
/// @file
/// @brief Combined mode (docs/methods/combined.md): the split plan, the split's energy
/// bookkeeping on a thick slab (nothing beyond r_s is dropped; the double-counted part is the
/// documented overlap), the limits r_s → ∞ (dipole alone) and r_s → 0 (SSLPV alone), the back-lit
/// thin-thick scene against a small reference path-traced image, and the GL provider (sum of its
/// parts; parity with the CPU formulas on the G-buffer it rendered).

#include "../dipole/DipoleTestUtil.h"

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/combined/Combined.h>
#include <lucent/combined/CombinedProvider.h>
#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/dipole/IrradiancePass.h>
#include <lucent/dipole/HalfSpace.h>
#include <lucent/dipole/Profiles.h>
#include <lucent/gpu/GlContext.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/material/Presets.h>
#include <lucent/material/Procedural.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/reference/PathTracer.h>
#include <lucent/scene/SceneFile.h>
#include <lucent/sslpv/GridDiffusion.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <epoxy/gl.h>
#include <gtest/gtest.h>
#include <shared/CombinedShared.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <vector>

using namespace lucent;
using namespace lucent::combined;

namespace {

constexpr float INF_F = std::numeric_limits<float>::infinity();
constexpr double PI_D = 3.14159265358979323846;

// The shared dipole test fixtures (tests/unit/dipole/DipoleTestUtil.h): the skin-like medium,
// the point-lit 10 mm sphere (32³ material, 1000 W/sr at (25, 20, 25) mm, η = 1.3) and the
// top-lit box.
using dipole::testutil::BoxLayout;
using dipole::testutil::boxScene;
using dipole::testutil::skinMaterial;

/// 10 mm sphere (4 subdivisions), 32³ skin-like material, point light, 40×40 pixels.
Scene litSphere() {
    return dipole::testutil::pointLitSphere(/*subdivisions=*/4, 40, 40);
}

CombinedSettings smallSettings(float splitRadius, SplitMode mode = SplitMode::Kernel) {
    CombinedSettings cs;
    cs.splitRadius = splitRadius;
    cs.mode = mode;
    cs.sslpv.gridResolution = 16;
    cs.sslpv.solver.maxSteps = 24;
    cs.dipole.importanceSamples = 12;
    cs.dipole.uniformSamples = 4;
    return cs;
}

void expectImagesEqual(const ImageRgb& a, const ImageRgb& b, float relTol, const char* what) {
    ASSERT_EQ(a.width(), b.width());
    ASSERT_EQ(a.height(), b.height());
    float peak = 0.f;
    for (int y = 0; y < b.height(); ++y)
        for (int x = 0; x < b.width(); ++x)
            peak = std::max(peak, luminance(b.at(x, y)));
    ASSERT_GT(peak, 0.f) << what;
    for (int y = 0; y < b.height(); ++y)
        for (int x = 0; x < b.width(); ++x)
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(a.at(x, y)[c], b.at(x, y)[c], relTol * std::abs(b.at(x, y)[c]))
                    << what << " at " << x << "," << y << " channel " << c;
}

/// skinMaterial() with more absorption: α′ 0.80 / 0.76 / 0.71 against the skin's 0.98 / 0.95 /
/// 0.91.
MaterialSample darkerSkin() {
    MaterialSample m = skinMaterial();
    m.sigma_t = m.sigma_s + Rgb(0.3f, 0.5f, 0.8f);
    return m;
}

/// Paints `m` into every inside voxel of `vol` whose centre has x > 0.
void paintHalfAbove(MaterialVolume& vol, const MaterialSample& m) {
    const int n = vol.resolution();
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x)
                if (vol.isInside({x, y, z}) && vol.spec().cellCenter({x, y, z}).x > 0.f)
                    vol.set({x, y, z}, m);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The split plan

TEST(CombinedSplit, PlanMapsRadiusToSkippedSteps) {
    // Steps: k = max(k₀, round(r_s/Δx)), capped at maxSteps + 1 (then SSLPV contributes nothing).
    const SplitMode st = SplitMode::Steps;
    SplitPlan p = planSplit(4.f, 1.f, 2, 32, st);
    EXPECT_EQ(p.skipSteps, 4);
    EXPECT_TRUE(p.dipoleOn && p.sslpvOn);
    EXPECT_FLOAT_EQ(p.dipoleMaxRadius(), 4.f);
    p = planSplit(1.f, 1.f, 2, 32, st);  // below k₀: SSLPV keeps its own skip
    EXPECT_EQ(p.skipSteps, 2);
    p = planSplit(-1.f, 0.5f, 2, 32, st);  // default: DEFAULT_SPLIT_CELLS cells
    EXPECT_FLOAT_EQ(p.splitRadius, DEFAULT_SPLIT_CELLS * 0.5f);
    EXPECT_EQ(p.skipSteps, int(DEFAULT_SPLIT_CELLS));
    p = planSplit(0.f, 1.f, 2, 32, st);  // SSLPV alone
    EXPECT_FALSE(p.dipoleOn);
    EXPECT_TRUE(p.sslpvOn);
    EXPECT_EQ(p.skipSteps, 2);
    p = planSplit(INF_F, 1.f, 2, 32, st);  // dipole alone, unlimited window
    EXPECT_TRUE(p.dipoleOn);
    EXPECT_FALSE(p.sslpvOn);
    EXPECT_EQ(p.dipoleMaxRadius(), 0.f);
    p = planSplit(1e9f, 1.f, 2, 32, st);  // any radius beyond the propagation: the same
    EXPECT_FALSE(p.sslpvOn);
    EXPECT_FLOAT_EQ(p.dipoleMaxRadius(), 1e9f);
    // Kernel: SSLPV always runs with its own skip; r_s is clamped to the kernel's reach.
    p = planSplit(4.f, 1.f, 2, 32);
    EXPECT_EQ(p.mode, SplitMode::Kernel);
    EXPECT_EQ(p.skipSteps, 2);
    EXPECT_TRUE(p.dipoleOn && p.sslpvOn);
    p = planSplit(0.f, 1.f, 2, 32);
    EXPECT_FALSE(p.dipoleOn);
    p = planSplit(INF_F, 0.5f, 2, 32);
    EXPECT_FLOAT_EQ(p.splitRadius, MAX_KERNEL_SPLIT_CELLS * 0.5f);
    EXPECT_THROW(planSplit(std::nanf(""), 1.f, 2, 32), ValueError);
    EXPECT_THROW(planSplit(1.f, 0.f, 2, 32), ValueError);
    EXPECT_THROW(planSplit(1.f, 1.f, -1, 32), ValueError);
}

// ---------------------------------------------------------------------------------------------
// Energy bookkeeping of the split on a thick slab (solver level, by superposition)

namespace {

/// G of the thick-slab half-space (sslpvHalfSpaceResponse, Δx = 1 mm, σt = 1 mm⁻¹, σs′ = α′,
/// η = 1.3), green channel, with SSLPV accumulating from step skip + 1 on; run until < 10⁻⁵ of
/// the injection is left.
std::vector<double> slabKernel(float albedo, int skip, int n, int half) {
    MaterialSample ms;
    ms.sigma_t = Rgb(1.f);
    ms.sigma_s = Rgb(albedo);
    sslpv::SslpvOptions o = CombinedSettings::defaultSslpvOptions().solver;
    o.skipAccumulateSteps = skip;
    o.maxSteps = 400;
    o.stopEpsilon = 1e-5f;
    std::vector<double> g;
    for (const Rgb& v : sslpvHalfSpaceResponse(ms, 1.3f, o, 1.f, n, half))
        g.push_back(double(v.g));
    return g;
}

}  // namespace

// The Steps split's claims, checked where everything is known (a homogeneous half-space,
// uniform irradiance by superposition of the point-injection kernel G): (1) SSLPV's skipped
// steps 1…k hold light only within k cells (Manhattan) of the source, so nothing from beyond
// r_s = k·Δx is dropped — exactly; (2) hence the combined L/E is the splice of the dipole near
// r_s and SSLPV beyond it plus the overlap O = Σ_{d ≤ r_s} G_k (late SSLPV light of near
// sources, counted twice): C = D_≤r_s + T_>r_s + O. The Kernel split's surface kernel is the
// same G in ring form: its integral to a ring edge is the ring sum (construction), so there the
// Kernel split's C is D_≤r_s + T_>r_s with no overlap.
TEST(CombinedSplit, ThickSlabStepsSplitDropsNothingFarAndDoubleCountsTheOverlap) {
    const int n = 39, half = 18;
    const int side = 2 * half + 1;
    const float eta = 1.3f;
    const double ft0 = 1.0 - fresnelDielectric(1.0, eta);
    for (float albedo : {0.8f, 0.95f}) {
        const std::vector<double> g0 = slabKernel(albedo, /*skip=*/2, n, half);  // SSLPV alone
        const dipole::ScalarMedium med = dipole::fromReduced(1.f, albedo, eta);
        const dipole::DipoleProfile prof = dipole::DipoleProfile::make(dipole::Model::Dipole, med);
        // Dipole L/E (without T(ω_o), like the kernel): F_t(0)·∫R_d dA/π (Jensen 2001 Eq. 4
        // integrated, Mertens et al. 2005 Table 1); the window integral by Simpson in r = R u².
        const auto windowed = [&](double R) {
            return ft0 * dipole::testutil::radialIntegral(prof, R) / PI_D;
        };
        const double dipoleAll = ft0 * prof.totalReflectance() / PI_D;
        double sslpvAll = 0.0;
        for (double v : g0)
            sslpvAll += v;
        // The ring kernel of the same SSLPV (Δx = 1 mm, the slab kernel's options).
        MaterialSample ms;
        ms.sigma_t = Rgb(1.f);
        ms.sigma_s = Rgb(albedo);
        sslpv::SslpvOptions ko = CombinedSettings::defaultSslpvOptions().solver;
        ko.maxSteps = 400;
        ko.stopEpsilon = 1e-5f;
        // r = 12 mm: a 39³ half-space with half = 18, the same as the kernels of this test.
        const SslpvSurfaceKernel kern = computeSslpvSurfaceKernel(ms, eta, ko, 1.f, 12.f);
        for (int k : {3, 4, 6}) {
            const double rs = double(k);  // Δx = 1 mm
            const std::vector<double> gk = slabKernel(albedo, k, n, half);
            double kept = 0.0, overlap = 0.0, droppedFar = 0.0, dropped = 0.0, farAll = 0.0;
            double ringNear = 0.0;  // Σ G_k0 over the rings 0..k (distances < k + ½ cells)
            for (int j = -half; j <= half; ++j)
                for (int i = -half; i <= half; ++i) {
                    const size_t idx = size_t(j + half) * size_t(side) + size_t(i + half);
                    const double d = std::hypot(double(i), double(j));
                    kept += gk[idx];
                    dropped += g0[idx] - gk[idx];
                    if (d <= rs)
                        overlap += gk[idx];
                    else
                        farAll += g0[idx];
                    if (std::floor(d + 0.5) <= double(k))
                        ringNear += g0[idx];
                    if (std::abs(i) + std::abs(j) > k)
                        droppedFar += std::abs(g0[idx] - gk[idx]);
                }
            // (1) exact: the accumulations differ only by additions of exact zeros there.
            EXPECT_EQ(droppedFar, 0.0) << "albedo " << albedo << " k " << k;
            const double local = windowed(rs);
            const double comb = local + kept;
            // (2) C = D_≤r_s + T_>r_s + O: float sums over ≤ 400 steps, 1e-5 relative.
            EXPECT_NEAR(comb, local + farAll + overlap, 1e-5 * comb);
            EXPECT_GT(overlap, 0.0);
            // Kernel ring form: ∫_0^{ρ_k} R_lpv 2πr dr = π Σ_{rings ≤ k} G / T(0) (1e-5: float).
            const double ringEdge = kern.ringOuter[size_t(k)];
            EXPECT_NEAR(double(kern.integral(float(ringEdge)).g) * ft0 / PI_D, ringNear,
                        1e-5 * ringNear);
            std::printf(
                "albedo %.2f k %d: dipole %.5f (<= r_s %.1f%%), sslpv %.5f (first k steps "
                "%.1f%%), steps split %.5f = %.3f x max, overlap %.5f (%.1f%% of it); "
                "splice without overlap %.3f x max\n",
                double(albedo), k, dipoleAll, 100.0 * local / dipoleAll, sslpvAll,
                100.0 * dropped / sslpvAll, comb, comb / std::max(dipoleAll, sslpvAll), overlap,
                100.0 * overlap / comb, (local + farAll) / std::max(dipoleAll, sslpvAll));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// CPU renderer: the limits

// The mean incidence the kernel is lit at (meanIncidenceCosine): on a flat face under a
// directional light it is that light's cosine; lights behind the face add nothing; at η = 1 on a
// sphere under a distant light it is ∫cos² / ∫cos over the lit hemisphere = 2/3 (rounded to the
// step); with no light the kernel stays at normal incidence.
TEST(CombinedKernel, MeanIncidenceIsTheIrradianceWeightedCosine) {
    TriangleMesh quad;  // 20 × 20 mm facing +z
    quad.positions = {
        {-10.f, -10.f, 0.f}, {10.f, -10.f, 0.f}, {10.f, 10.f, 0.f}, {-10.f, 10.f, 0.f}};
    quad.triangles = {{0u, 1u, 2u}, {0u, 2u, 3u}};
    const auto sun = [](float cosI) {
        Light l;
        l.type = Light::Type::Directional;
        l.direction = -Vector3f(std::sqrt(1.f - cosI * cosI), 0.f, cosI);
        l.intensity = Rgb(1.f);
        return l;
    };
    for (float c : {1.f, 0.8f, 0.35f})
        EXPECT_FLOAT_EQ(meanIncidenceCosine(quad, {sun(c)}, 1.3f), c) << c;
    Light below = sun(0.6f);
    below.direction = -below.direction;
    EXPECT_FLOAT_EQ(meanIncidenceCosine(quad, {sun(0.8f), below}, 1.3f), 0.8f);
    EXPECT_FLOAT_EQ(meanIncidenceCosine(quad, {below}, 1.3f), 1.f);
    EXPECT_FLOAT_EQ(meanIncidenceCosine(quad, {}, 1.3f), 1.f);
    // Two lights of equal irradiance at cosines 1 and 0.5: weights E·cos, mean (1 + ¼)/(1.5).
    EXPECT_FLOAT_EQ(meanIncidenceCosine(quad, {sun(1.f), sun(0.5f)}, 1.f),
                    std::round(1.25f / 1.5f / KERNEL_INCIDENCE_STEP) * KERNEL_INCIDENCE_STEP);
    const TriangleMesh sphere = makeSphere(10.f, 5);
    EXPECT_FLOAT_EQ(meanIncidenceCosine(sphere, {sun(1.f)}, 1.f), 0.65f);
}

// An oblique beam scatters first nearer the surface, so more of it leaves: the kernel lit at
// the scene's mean incidence holds SSLPV's own gain over the kernel lit head-on. Its direction
// and size are checked against the exact half-space (adding–doubling, dipole::HalfSpace.h):
// the kernel's total per unit transmitted irradiance at outside cosine μ_i over that at normal
// incidence, against R(α′, η, μ_t) / R(α′, η, 1) at the refracted cosine μ_t.
TEST(CombinedKernel, ObliqueIncidenceGainFollowsTheExactHalfSpace) {
    const float eta = 1.3f;
    sslpv::SslpvOptions o = CombinedSettings::defaultSslpvOptions().solver;
    o.mode = sslpv::SslpvMode::Diffusion;
    for (float albedo : {0.8f, 0.99f}) {
        MaterialSample ms;
        ms.sigma_t = Rgb(1.f);
        ms.sigma_s = Rgb(albedo);
        const float cellSize = 0.5f, radius = 8.f;
        const SslpvSurfaceKernel head = computeSslpvSurfaceKernel(ms, eta, o, cellSize, radius);
        const double headTotal = double(head.integral(radius).g);
        const double exactHead = dipole::halfSpaceReflectance(albedo, eta, 1.0);
        for (float cosI : {0.75f, 0.5f}) {
            const SslpvSurfaceKernel tilted =
                computeSslpvSurfaceKernel(ms, eta, o, cellSize, radius, cosI);
            EXPECT_EQ(tilted.ringOuter, head.ringOuter);
            const double gain = double(tilted.integral(radius).g) / headTotal;
            const double sinT = std::sqrt(1.0 - double(cosI) * double(cosI)) / double(eta);
            const double exactGain =
                dipole::halfSpaceReflectance(albedo, eta, std::sqrt(1.0 - sinT * sinT)) / exactHead;
            std::printf("albedo %.2f, cos %.2f: kernel gain %.4f, exact %.4f\n", double(albedo),
                        double(cosI), gain, exactGain);
            // Measured 2026-12-07: 1.065 / 1.124 against 1.059 / 1.112 (α′ 0.8), 1.029 / 1.053
            // against 1.020 / 1.037 (α′ 0.99). Head-on the kernel's gain is 1, off by the whole
            // exact gain − 1; lit at the incidence it must be off by at most half of that.
            EXPECT_GT(gain, 1.0);
            EXPECT_LE(std::abs(gain - exactGain), 0.5 * (exactGain - 1.0));
        }
    }
}

TEST(CombinedCpu, InfiniteSplitEqualsDipoleAlone) {
    const Scene s = litSphere();
    const CombinedSettings cs = smallSettings(INF_F, SplitMode::Steps);
    const CombinedResult r = renderCombined(s, cs);
    EXPECT_FALSE(r.plan.sslpvOn);
    dipole::GatherSettings gs = cs.dipole;
    gs.maxRadius = 0.f;
    dipole::LightViewSettings cameraOnly;  // CombinedSettings::dipoleLightViews = false
    cameraOnly.enabled = false;
    const ImageRgb alone = dipole::renderImageSpaceDipole(s, gs, cameraOnly).radiance;
    // Same code and samples: equal up to the float addition of an exact 0.
    expectImagesEqual(r.radiance, alone, 0.f, "r_s = inf vs dipole");
    // A radius far beyond the object (and the propagation) is the same limit: the window then
    // removes nothing (all samples lie within 4·R of the 10 mm sphere... and r ≤ 1e6 mm).
    const CombinedResult big = renderCombined(s, smallSettings(1e6f, SplitMode::Steps));
    EXPECT_FALSE(big.plan.sslpvOn);
    expectImagesEqual(big.radiance, alone, 1e-6f, "r_s = 1e6 mm vs dipole");
}

TEST(CombinedCpu, ZeroSplitEqualsSslpvAlone) {
    const Scene s = litSphere();
    for (SplitMode mode : {SplitMode::Kernel, SplitMode::Steps}) {
        const CombinedSettings cs = smallSettings(0.f, mode);
        const CombinedResult r = renderCombined(s, cs);
        EXPECT_FALSE(r.plan.dipoleOn);
        EXPECT_EQ(r.plan.skipSteps, cs.sslpv.solver.skipAccumulateSteps);
        const ImageRgb alone = sslpv::renderSslpv(s, cs.sslpv);
        expectImagesEqual(r.radiance, alone, 0.f, "r_s = 0 vs sslpv");
    }
}

TEST(CombinedCpu, IntermediateStepsSplitIsTheSumOfBothWindowedParts) {
    const Scene s = litSphere();
    const CombinedSettings cs = smallSettings(-1.f, SplitMode::Steps);  // default: 4 cells
    const CombinedResult r = renderCombined(s, cs);
    ASSERT_TRUE(r.plan.dipoleOn && r.plan.sslpvOn);
    EXPECT_EQ(r.plan.skipSteps, int(DEFAULT_SPLIT_CELLS));
    // The parts against their methods run directly with the plan's window and skip.
    dipole::GatherSettings gs = cs.dipole;
    gs.maxRadius = r.plan.splitRadius;
    dipole::LightViewSettings cameraOnly;
    cameraOnly.enabled = false;
    expectImagesEqual(r.dipole, dipole::renderImageSpaceDipole(s, gs, cameraOnly).radiance, 0.f,
                      "dipole part");
    sslpv::SslpvRenderOptions so = cs.sslpv;
    so.solver.skipAccumulateSteps = r.plan.skipSteps;
    expectImagesEqual(r.sslpv, sslpv::renderSslpv(s, so), 0.f, "sslpv part");
    // Each part is at most its method alone (a window and a skip only remove light).
    const ImageRgb dAll = renderCombined(s, smallSettings(INF_F, SplitMode::Steps)).radiance;
    const ImageRgb lAll = renderCombined(s, smallSettings(0.f, SplitMode::Steps)).radiance;
    double sd = 0, sdAll = 0, sl = 0, slAll = 0;
    for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 40; ++x) {
            sd += luminance(r.dipole.at(x, y));
            sdAll += luminance(dAll.at(x, y));
            sl += luminance(r.sslpv.at(x, y));
            slAll += luminance(lAll.at(x, y));
        }
    EXPECT_GT(sd, 0.0);
    EXPECT_GT(sl, 0.0);
    // The window keeps the same samples inside r_s: sum ≤ unwindowed (1e-6: float order).
    EXPECT_LE(sd, sdAll * (1 + 1e-6));
    EXPECT_LE(sl, slAll * (1 + 1e-6));
}

// Both SSLPV parts: the calibrated propagation and the diffusion mode (the method's default,
// docs/methods/combined.md "The SSLPV part"), whose kernel is the diffusion solve's response.
TEST(CombinedCpu, KernelSplitIsSslpvPlusDipoleMinusItsLocalPart) {
    const Scene s = litSphere();
    for (const bool diffusion : {false, true}) {
        SCOPED_TRACE(diffusion ? "diffusion part" : "calibrated part");
        CombinedSettings cs = smallSettings(-1.f);
        if (diffusion) {  // as the combined method sets its default part
            cs.sslpv.solver.mode = sslpv::SslpvMode::Diffusion;
            cs.sslpv.injectionResolution = 64;
            cs.sslpv.solver.maxSteps = 1024;
            cs.sslpv.solver.stopEpsilon = 1e-3f;
        }
        const CombinedResult r = renderCombined(s, cs);
        ASSERT_TRUE(r.plan.dipoleOn && r.plan.sslpvOn);
        EXPECT_EQ(r.plan.skipSteps, cs.sslpv.solver.skipAccumulateSteps);
        expectImagesEqual(r.sslpv, sslpv::renderSslpv(s, cs.sslpv), 0.f, "sslpv part (unchanged)");
        // The kernel is lit at the scene's mean incidence (about 45° here, a point light over
        // the sphere's front).
        const float incidence = meanIncidenceCosine(s.objects[0].mesh, s.lights, s.eta);
        EXPECT_LT(incidence, 1.f);
        const SslpvSurfaceKernel k = computeSslpvSurfaceKernel(
            meanInsideMaterial(*s.objects[0].material), s.eta, cs.sslpv.solver, r.plan.cellSize,
            r.plan.splitRadius, incidence);
        ASSERT_FALSE(k.ringValue.empty());
        EXPECT_GT(luminance(k.ringValue[0]), 0.f);
        const dipole::SurfaceBuffers buf = dipole::buildSurfaceBuffers(s);
        const ImageRgb lhat =
            localSslpvEstimate(buf, k, r.plan.splitRadius, s.eta, cs.localSamples, cs.dipole.seed);
        const ImageRgb f =
            localSslpvFraction(buf, k, r.plan.splitRadius, cs.localSamples, cs.dipole.seed);
        ImageRgb want(40, 40);
        for (int y = 0; y < 40; ++y)
            for (int x = 0; x < 40; ++x) {
                for (int c = 0; c < 3; ++c)
                    ASSERT_TRUE(f.at(x, y)[c] >= 0.f && f.at(x, y)[c] <= 1.f);
                want.at(x, y) = glm::min(lhat.at(x, y), f.at(x, y) * r.sslpv.at(x, y));
            }
        // (With the diffusion part on a painted volume L̂ is carried to the albedo the read-out
        // sees, localScaleToSurfaceMaterial; on this homogeneous sphere that is skipped.)
        expectImagesEqual(r.local, want, 0.f, "local part min(L^, f * L_sslpv)");
        double sl = 0, sloc = 0;
        for (int y = 0; y < 40; ++y)
            for (int x = 0; x < 40; ++x) {
                const Rgb want =
                    glm::max(r.dipole.at(x, y) + r.sslpv.at(x, y) - r.local.at(x, y), Rgb(0.f));
                for (int c = 0; c < 3; ++c)
                    ASSERT_EQ(r.radiance.at(x, y)[c], want[c]);
                sl += luminance(r.sslpv.at(x, y));
                sloc += luminance(r.local.at(x, y));
            }
        // The local estimate is a part of SSLPV's light, not all of it (the sphere's far side
        // and the terminator are lit from beyond r_s).
        EXPECT_GT(sloc, 0.0);
        EXPECT_LT(sloc, sl);
    }
}

// Front-lit large slab, directional light along −n, orthographic camera from above: E is
// uniform, so at the centre the Kernel split must give exactly its bookkeeping,
//   L = L_sslpv + F_t(0)²·E/π·∫_{r≤r_s} R_d 2πr dr − min(F_t(0)²·E/π·∫_{r≤r_s} R_lpv, f·L_sslpv),
//   f = ∫_{≤r_s} R_lpv / ∫ R_lpv,
// within the Monte Carlo error of the two gathers (per-pixel spread over a block).
TEST(CombinedCpu, KernelSplitOnFrontLitSlabMatchesItsBookkeeping) {
    const Scene s = boxScene(skinMaterial(), {.size = {240.f, 240.f, 20.f},
                                              .grid = 64,
                                              .cameraHeight = 100.f,
                                              .viewHeight = 160.f,
                                              .pixels = 48});
    CombinedSettings cs;
    cs.sslpv.gridResolution = 32;
    cs.splitRadius = 40.f;  // mm: ≈ 5 cells of 7.9 mm, inside the image around the centre
    cs.dipole.importanceSamples = 48;
    cs.dipole.uniformSamples = 16;
    cs.localSamples = 64;
    const CombinedResult r = renderCombined(s, cs);
    const float rs = r.plan.splitRadius;
    const SslpvSurfaceKernel k =
        computeSslpvSurfaceKernel(skinMaterial(), s.eta, cs.sslpv.solver, r.plan.cellSize, rs);
    const dipole::Boundary bnd = dipole::Boundary::of(s.eta);
    const double ft0 = 1.0 - fresnelDielectric(1.0, s.eta);
    for (int c = 0; c < 3; ++c) {
        const dipole::ScalarMedium med =
            dipole::fromReduced(skinMaterial().sigma_t[c], skinMaterial().sigma_s[c], s.eta);
        const dipole::DipoleProfile prof =
            dipole::DipoleProfile::make(dipole::Model::Dipole, med.sigma_a, med.sigma_s, bnd);
        const double dLoc = dipole::testutil::radialIntegral(prof, rs);  // Simpson, r = R u²
        const double E = ft0 * 1.0;  // transmitted irradiance, W/mm²
        // Uniform E: the near fraction is the kernel's own (its outer ring as the renderer's).
        const double frac = double(k.integral(rs)[c]) / double(k.integral(INF_F)[c]);
        const double dipoleNear = ft0 * E / PI_D * dLoc;
        double sum = 0.0, sum2 = 0.0, ref = 0.0;
        int count = 0;
        for (int y = 20; y < 28; ++y)
            for (int x = 20; x < 28; ++x) {
                const double lpv = double(r.sslpv.at(x, y)[c]);
                const double lhat = ft0 * E / PI_D * double(k.integral(rs)[c]);
                const double want = lpv + dipoleNear - std::min(lhat, frac * lpv);
                const double d = double(r.radiance.at(x, y)[c]) - want;
                sum += d;
                sum2 += d * d;
                ref += want;
                ++count;
            }
        const double mean = sum / count;
        const double se = std::sqrt(std::max(0.0, sum2 / count - mean * mean) / (count - 1));
        std::printf(
            "slab channel %d: combined %.5g, bookkeeping %.5g (dipole window %.4f, "
            "SSLPV kernel near fraction %.4f), SE %.2g\n",
            c, sum / count + ref / count, ref / count, dLoc, frac, se);
        // 4 standard errors of the per-pixel spread (interleaved shifts decorrelate pixels),
        // plus 1e-3 relative for Simpson and float sums.
        EXPECT_NEAR(mean, 0.0, 4 * se + 1e-3 * ref / count) << "channel " << c;
    }
}

// Issue 6: at η = 1 the Kernel split lost 20–50 % of the light (docs/evaluation.md, presets × η).
// The flat half-space kernel R_lpv overstates what SSLPV deposits on the voxelised sphere, and at
// η = 1 (calibrated exit gain G/η², Børlum et al. 2011 Eq. 7 as calibrated in
// docs/methods/sslpv.md) its absolute local integral exceeds the dipole's by 36 % for marble: the
// old subtraction F_t/π ∫_{≤r_s} R_lpv E dA removed more than SSLPV's whole image held. The split
// must keep its two limits: SSLPV's subtracted part is a share of SSLPV's own radiance (0 ≤
// f·L_sslpv ≤ L_sslpv per pixel), and the total is the splice of the two parts' energies,
//   Σ L ≥ (f_D + 1 − f_S) · min(Σ L_dipole, Σ L_sslpv),
// f_D = ∫_{≤r_s} R_d / ∫ R_d (Jensen 2001 Eq. 4 via Mertens et al. 2005 Table 1) and f_S the
// kernel's near fraction, less the gathers' Monte Carlo error.
TEST(CombinedCpu, KernelSplitKeepsThePartsEnergyAtEtaOne) {
    Scene s = litSphere();
    s.eta = 1.f;
    const MaterialSample marble = findPreset("marble").sample();
    s.objects[0].material = std::make_shared<MaterialVolume>(s.objects[0].material->spec(), marble);
    CombinedSettings cs;  // the CLI's defaults: grid 32, r_s = 4 cells
    const CombinedResult r = renderCombined(s, cs);
    ASSERT_TRUE(r.plan.dipoleOn && r.plan.sslpvOn);
    CombinedSettings dOnly = cs;
    dOnly.splitRadius = INF_F;
    dOnly.mode = SplitMode::Steps;  // r_s = ∞: the dipole alone (camera image, as the split)
    const ImageRgb dip = renderCombined(s, dOnly).radiance;
    glm::dvec3 sumL(0.0), sumD(0.0), sumS(0.0), sumLocal(0.0);
    for (int y = 0; y < s.camera.height; ++y)
        for (int x = 0; x < s.camera.width; ++x) {
            for (int c = 0; c < 3; ++c) {
                ASSERT_GE(r.local.at(x, y)[c], 0.f) << x << "," << y;
                ASSERT_LE(r.local.at(x, y)[c], r.sslpv.at(x, y)[c]) << x << "," << y;
            }
            sumL += glm::dvec3(r.radiance.at(x, y));
            sumD += glm::dvec3(dip.at(x, y));
            sumS += glm::dvec3(r.sslpv.at(x, y));
            sumLocal += glm::dvec3(r.local.at(x, y));
        }
    const SslpvSurfaceKernel k = computeSslpvSurfaceKernel(
        marble, s.eta, cs.sslpv.solver, r.plan.cellSize, r.plan.splitRadius,
        meanIncidenceCosine(s.objects[0].mesh, s.lights, s.eta));
    const float rs = r.plan.splitRadius;
    for (int c = 0; c < 3; ++c) {
        const dipole::ScalarMedium med =
            dipole::fromReduced(marble.sigma_t[c], marble.sigma_s[c], s.eta);
        const dipole::DipoleProfile prof = dipole::DipoleProfile::make(
            dipole::Model::Dipole, med.sigma_a, med.sigma_s, dipole::Boundary::of(s.eta));
        const double fD = dipole::testutil::radialIntegral(prof, rs) / prof.totalReflectance();
        const double fS = double(k.integral(rs)[c]) / double(k.integral(INF_F)[c]);
        const double splice = std::min(1.0, fD + 1.0 - fS);
        const double lower = splice * std::min(sumD[c], sumS[c]);
        std::printf(
            "eta 1 marble channel %d: combined %.4g, dipole %.4g, SSLPV %.4g (local part "
            "%.4g); f_D %.3f, f_S %.3f: splice bound %.4g\n",
            c, sumL[c], sumD[c], sumS[c], sumLocal[c], fD, fS, lower);
        // 5 %: the windowed and the full dipole gathers are separate Monte Carlo estimates
        // (12 + 4 samples/pixel at the defaults' spread, docs/methods/dipole.md) and the
        // near fraction f is estimated by 32 samples per pixel on each side.
        EXPECT_GE(sumL[c], 0.95 * lower) << "channel " << c;
    }
}

TEST(CombinedCpu, KernelMaterialIsTheSurfaceCellsMean) {
    // The local kernel is solved for the material of the volume's surface cells (surfaceShell,
    // one SSLPV cell deep), not the whole inside's mean: a coat over another core is the coat's.
    const Scene s = litSphere();
    MaterialVolume vol = *s.objects[0].material;
    const float h = vol.spec().voxelSize;
    const std::vector<Coord> firstLayer = surfaceShell(vol, 0.f);  // at least the first layer
    const std::vector<Coord> shell = surfaceShell(vol, 2.f * h);
    ASSERT_FALSE(firstLayer.empty());
    EXPECT_GT(shell.size(), firstLayer.size());
    EXPECT_TRUE(std::includes(shell.begin(), shell.end(), firstLayer.begin(), firstLayer.end(),
                              [&](const Coord& a, const Coord& b) {
                                  return vol.spec().linearIndex(a) < vol.spec().linearIndex(b);
                              }));
    // The box of radius 2 voxels: every inside voxel within Euclidean distance 2 of an outside
    // voxel centre is in it, none beyond 2√3 (distanceToSurface's depth is (d − ½)·h).
    const std::vector<float> depth = distanceToSurface(vol);
    std::vector<uint8_t> inShell(depth.size(), 0);
    for (const Coord& c : shell)
        inShell[vol.spec().linearIndex(c)] = 1;
    const int n = vol.resolution();
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const Coord c(x, y, z);
                const size_t i = vol.spec().linearIndex(c);
                if (!vol.isInside(c))
                    continue;
                if (depth[i] <= 1.5f * h) {
                    EXPECT_TRUE(inShell[i]) << x << "," << y << "," << z;
                }
                if (depth[i] > (2.f * std::sqrt(3.f) - 0.5f) * h + 1e-4f) {
                    EXPECT_FALSE(inShell[i]) << x << "," << y << "," << z;
                }
            }
    // Homogeneous: the same as the inside's mean.
    const MaterialSample skin = skinMaterial();
    EXPECT_NEAR(surfaceMaterial(vol, shell).sigma_t.g, meanInsideMaterial(vol).sigma_t.g,
                1e-5f * skin.sigma_t.g);
    // A dark core under a skin coat 3 voxels deep, which holds the whole shell.
    MaterialSample core = skin;
    core.sigma_t = core.sigma_s + Rgb(1.f);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const Coord c(x, y, z);
                if (vol.isInside(c) && depth[vol.spec().linearIndex(c)] > 3.f * h)
                    vol.set(c, core);
            }
    const MaterialSample coat = surfaceMaterial(vol, surfaceShell(vol, 2.f * h));
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(coat.sigma_t[c], skin.sigma_t[c], 1e-5f * skin.sigma_t[c]) << c;
        EXPECT_NEAR(coat.sigma_s[c], skin.sigma_s[c], 1e-5f * skin.sigma_s[c]) << c;
        EXPECT_GT(meanInsideMaterial(vol).sigma_t[c], skin.sigma_t[c] + 0.1f) << c;
    }
    EXPECT_THROW(surfaceShell(vol, std::numeric_limits<float>::quiet_NaN()), ValueError);
    EXPECT_THROW(surfaceMaterial(vol, {}), ValueError);
}

// dipoleNearShare against DipoleProfile's closed forms in double (totalReflectance,
// reflectanceBeyond): float rounding only, at radii from a tenth of a mean free path to many
// diffusion lengths and albedos from dark to white.
TEST(CombinedCpu, NearShareIsTheClassicalDipolesShareWithinTheRadius) {
    const dipole::Boundary boundary = dipole::Boundary::of(1.3);
    const float A = float((1.0 + boundary.fdr) / (1.0 - boundary.fdr));
    for (const float sigmaT : {0.2f, 1.f, 8.f})
        for (const float albedo : {0.3f, 0.9f, 0.999f, 1.f})
            for (const float r : {0.01f, 0.5f, 3.f, 40.f}) {
                const dipole::DipoleProfile p = dipole::DipoleProfile::make(
                    dipole::Model::Dipole, double(sigmaT) * (1.0 - albedo), double(sigmaT) * albedo,
                    boundary);
                const double want = 1.0 - p.reflectanceBeyond(r) / p.totalReflectance();
                EXPECT_NEAR(dipoleNearShare(sigmaT, albedo, A, r), want, 2e-5)
                    << sigmaT << ' ' << albedo << ' ' << r;
            }
    EXPECT_EQ(dipoleNearShare(0.f, 0.9f, A, 1.f), 0.f);
    EXPECT_LT(dipoleNearShare(1.f, 0.99f, A, 1.f), dipoleNearShare(1.f, 0.5f, A, 1.f));
    EXPECT_LT(dipoleNearShare(0.2f, 0.9f, A, 1.f), dipoleNearShare(2.f, 0.9f, A, 1.f));
}

// discMeanMaterial on a slab seen from above, painted in two halves at x = 0: a pixel further
// than r_s from the seam reads its own half's material exactly; one on the seam reads the halves'
// mean, the Hammersley points split by the seam as the disc's area is (half each, to within one
// of the 16 points); the background's points (no material) are left out; an uncovered pixel reads
// nothing.
TEST(CombinedCpu, DiscMeanMaterialAveragesTheSurfaceWithinTheRadius) {
    const MaterialSample skin = skinMaterial(), dark = darkerSkin();
    const int n = 64;
    dipole::SurfaceBuffers buf;
    buf.resize(n, n);
    buf.orthographic = true;
    buf.viewDirection = Vector3f(0.f, 0.f, -1.f);
    // x, y in [-32, 32] mm onto the pixels (1 mm each; row 0 at the top, y = +32).
    buf.clipFromWorld = glm::ortho(-32.f, 32.f, -32.f, 32.f, -100.f, 100.f);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const size_t i = buf.index(x, y);
            buf.position[i] = Point3f(float(x) - 31.5f, 31.5f - float(y), 0.f);
            buf.normal[i] = Normal3f(0.f, 0.f, 1.f);
            if (x >= n - 4)
                continue;  // the last four columns are background: uncovered, no material
            buf.covered[i] = 1;
            buf.material[i] = x < n / 2 ? skin : dark;
        }
    const float rs = 6.f;
    const MaterialSample own = discMeanMaterial(buf, 10, 30, rs);
    for (int c = 0; c < 3; ++c) {
        EXPECT_FLOAT_EQ(own.sigma_t[c], skin.sigma_t[c]) << c;
        EXPECT_FLOAT_EQ(own.sigma_s[c], skin.sigma_s[c]) << c;
    }
    const MaterialSample seam = discMeanMaterial(buf, n / 2, 30, rs);
    const float step = 1.f / float(LUCENT_COMBINED_DISC_MEAN_SAMPLES);
    for (int c = 0; c < 3; ++c) {
        const float w = (seam.sigma_t[c] - skin.sigma_t[c]) / (dark.sigma_t[c] - skin.sigma_t[c]);
        EXPECT_NEAR(w, 0.5f, step + 1e-4f) << c;
        EXPECT_NEAR(seam.sigma_s[c], skin.sigma_s[c] + w * (dark.sigma_s[c] - skin.sigma_s[c]),
                    1e-4f * skin.sigma_s[c])
            << c;
    }
    const MaterialSample edge = discMeanMaterial(buf, n - 6, 30, rs);
    for (int c = 0; c < 3; ++c)
        EXPECT_FLOAT_EQ(edge.sigma_t[c], dark.sigma_t[c]) << c;
    EXPECT_EQ(discMeanMaterial(buf, n - 1, 30, rs).sigma_t, Rgb(0.f));
}

TEST(CombinedCpu, LocalScaleIsTheRatioOfExactTotalsTimesNearShares) {
    const std::shared_ptr<const sslpv::ExactReflectanceRatio> table =
        sslpv::exactReflectanceRatio(1.3);
    const float rs = 2.f;
    const MaterialSample kernelMaterial{Rgb(2.f, 1.5f, 4.f), Rgb(1.8f, 1.2f, 3.8f), Rgb(0.f)};
    const Rgb kernel = reducedAlbedo(kernelMaterial);
    const KernelSurfaceTerms terms = kernelSurfaceTerms(kernelMaterial, 1.3f, rs, *table);
    EXPECT_THROW(kernelSurfaceTerms(kernelMaterial, 0.5f, rs, *table), ValueError);
    const Rgb same = localScaleToSurfaceMaterial(kernel, kernelMaterial, terms, *table);
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(same[c], 1.f, 1e-6f) << c;
    // A darker, a lighter and a far darker surface without σt′: the exact half-space totals'
    // ratio, within the table's linear interpolation over 64 intervals in u = sqrt(1 - alpha')
    // (its error against the exact solve stays under 0.2 % at these albedos).
    const Rgb surface(0.5f, 0.99f, 0.1f);
    const Rgb totals = localScaleToSurfaceMaterial(surface, MaterialSample{}, terms, *table);
    for (int c = 0; c < 3; ++c) {
        const double want = dipole::halfSpaceReflectance(surface[c], 1.3) /
                            dipole::halfSpaceReflectance(kernel[c], 1.3);
        EXPECT_NEAR(totals[c], want, 2e-3 * want) << c;
    }
    EXPECT_LT(totals.r, 1.f);
    EXPECT_GT(totals.g, 1.f);
    // With the material around x_o, times the near shares' ratio at its albedo: a surface as
    // translucent as jade (σt′ a tenth of the kernel's) keeps less of its light within r_s than
    // the kernel's material, a denser one more.
    const Rgb sigmaT(0.2f, 15.f, 0.4f), discAlbedo(0.7f, 0.95f, 0.2f);
    const MaterialSample disc{sigmaT, sigmaT * discAlbedo, Rgb(0.f)};
    const Rgb scale = localScaleToSurfaceMaterial(surface, disc, terms, *table);
    const dipole::Boundary boundary = dipole::Boundary::of(1.3);
    const auto share = [&](double st, double a) {
        const dipole::DipoleProfile p =
            dipole::DipoleProfile::make(dipole::Model::Dipole, st * (1.0 - a), st * a, boundary);
        return 1.0 - p.reflectanceBeyond(rs) / p.totalReflectance();
    };
    for (int c = 0; c < 3; ++c) {
        const double want = double(totals[c]) * share(sigmaT[c], discAlbedo[c]) /
                            share(kernelMaterial.sigma_t[c], kernel[c]);
        EXPECT_NEAR(scale[c], want, 1e-4 * want) << c;
    }
    EXPECT_LT(scale.r, totals.r);
    EXPECT_GT(scale.g, totals.g);
    // A channel where the read-out saw no cell keeps the kernel's part.
    const Rgb none = localScaleToSurfaceMaterial(Rgb(0.f, 0.5f, 0.f), disc, terms, *table);
    EXPECT_EQ(none.r, 1.f);
    EXPECT_EQ(none.b, 1.f);
    EXPECT_LT(none.g, 1.f);
}

// A front-lit slab painted half skin, half a darker medium: the kernel is solved for the mean of
// the surface cells, which is neither half. With L̂ carried to the albedo the diffusion part reads
// at x_o, the middle of each half (25 mm from the seam: 6.8 diffusion lengths of the skin's red,
// the longest; r_s = 4 cells of 1.6 mm) reads nearer what a slab of that half's material alone
// reads: the SSLPV and dipole parts there are that slab's (checked), so the subtracted local part
// is all that differs, and the scaled mean kernel shares the half's total, not its radial shape.
// (On cells much coarser than the diffusion length the discrete kernel's total no longer follows
// the exact half-space's: at 7.9 mm cells the scale took off only a third; docs/methods/
// combined.md, "The kernel at the painted surface".)
TEST(CombinedCpu, KernelAtThePaintedSurfaceGivesEachHalfItsOwnMaterialsLight) {
    const MaterialSample dark = darkerSkin();
    const BoxLayout layout{.size = {100.f, 100.f, 16.f},
                           .grid = 96,
                           .cameraHeight = 100.f,
                           .viewHeight = 100.f,
                           .pixels = 48};
    CombinedSettings cs;
    cs.sslpv.gridResolution = 64;
    cs.sslpv.solver.mode = sslpv::SslpvMode::Diffusion;  // as the combined method's default part
    cs.sslpv.solver.maxSteps = 1024;
    cs.sslpv.solver.stopEpsilon = 1e-3f;
    cs.splitRadius = -1.f;  // 4 cells
    cs.dipole.importanceSamples = 48;
    cs.dipole.uniformSamples = 16;
    cs.localSamples = 64;
    cs.autoSkipSslpv = false;  // the dipole's tail beyond r_s is negligible here: keep both
    Scene painted = boxScene(skinMaterial(), layout);
    MaterialVolume& vol = *painted.objects[0].material;
    paintHalfAbove(vol, dark);
    const CombinedResult two = renderCombined(painted, cs);
    ASSERT_TRUE(two.plan.dipoleOn && two.plan.sslpvOn);
    // The same renders' parts with the kernel's L̂ unscaled (the split as it was).
    const dipole::SurfaceBuffers buf = dipole::buildSurfaceBuffers(painted);
    const SslpvSurfaceKernel kernel = computeSslpvSurfaceKernel(
        surfaceMaterial(vol, surfaceShell(vol, two.plan.cellSize)), painted.eta, cs.sslpv.solver,
        two.plan.cellSize, two.plan.splitRadius,
        meanIncidenceCosine(painted.objects[0].mesh, painted.lights, painted.eta));
    const ImageRgb lhat = localSslpvEstimate(buf, kernel, two.plan.splitRadius, painted.eta,
                                             cs.localSamples, cs.dipole.seed);
    const ImageRgb frac =
        localSslpvFraction(buf, kernel, two.plan.splitRadius, cs.localSamples, cs.dipole.seed);
    for (const bool darkHalf : {false, true}) {
        const CombinedResult alone =
            renderCombined(boxScene(darkHalf ? dark : skinMaterial(), layout), cs);
        const int x0 =
            darkHalf ? 34 : 10;  // pixel columns 10-13 and 34-37: x = -70..-50, 50..70 mm
        for (int c = 0; c < 3; ++c) {
            double withScale = 0.0, without = 0.0, own = 0.0;
            for (int y = 22; y < 26; ++y)
                for (int x = x0; x < x0 + 4; ++x) {
                    ASSERT_NEAR(two.sslpv.at(x, y)[c], alone.sslpv.at(x, y)[c],
                                1e-3f * alone.sslpv.at(x, y)[c]);
                    ASSERT_NEAR(two.dipole.at(x, y)[c], alone.dipole.at(x, y)[c],
                                1e-3f * alone.dipole.at(x, y)[c]);
                    const float s = two.sslpv.at(x, y)[c], d = two.dipole.at(x, y)[c];
                    withScale += two.radiance.at(x, y)[c];
                    without +=
                        std::max(0.f, d + s - std::min(lhat.at(x, y)[c], frac.at(x, y)[c] * s));
                    own += alone.radiance.at(x, y)[c];
                }
            const double errWith = std::abs(withScale / own - 1.0),
                         errWithout = std::abs(without / own - 1.0);
            std::printf(
                "%s half, channel %d: painted slab / own material's slab %.4f with the "
                "scale, %.4f without\n",
                darkHalf ? "dark" : "skin", c, withScale / own, without / own);
            // Skin half: L̂ binds (it is below f·L_sslpv) and the scale takes away at least half
            // of the mismatch (measured 64-80 %); what is left is the discrete kernel's radial
            // shape, which the classical dipole's near share stands for only roughly. Dark half:
            // f·L_sslpv binds with or without the scale (the near share of the mean's kernel: 3 %
            // dark either way).
            if (darkHalf)
                EXPECT_LE(errWith, errWithout + 1e-4) << "dark " << c;
            else
                EXPECT_LT(errWith, errWithout / 2.0) << "skin " << c;
        }
    }
}

TEST(CombinedCpu, RejectsSceneWithoutMaterialAndNanSplit) {
    Scene s = litSphere();
    CombinedSettings cs = smallSettings(std::nanf(""));
    EXPECT_THROW(renderCombined(s, cs), ValueError);
    s.objects[0].material.reset();
    EXPECT_THROW(renderCombined(s, smallSettings(1.f)), ValueError);
}

// ---------------------------------------------------------------------------------------------
// The automatic SSLPV skip (applyFarSkip, docs/methods/combined.md "Automatic skip")

namespace {

/// Strongly absorbing medium: σa = 2, σs′ = 1 mm⁻¹, σ_tr = √(3·2·3) = 4.2 mm⁻¹ (1/σ_tr = 0.24 mm).
MaterialSample absorbingMaterial() {
    MaterialSample m;
    m.sigma_s = Rgb(1.f);
    m.sigma_t = Rgb(3.f);
    return m;
}

Scene absorbingSphere() {
    Scene s = litSphere();
    s.objects[0].material =
        std::make_shared<MaterialVolume>(s.objects[0].material->spec(), absorbingMaterial());
    return s;
}

/// Largest per-pixel |a − b| (luminance) over the peak luminance of `ref`.
double maxChangeOverPeak(const ImageRgb& a, const ImageRgb& b, const ImageRgb& ref) {
    double change = 0.0, peak = 0.0;
    for (int y = 0; y < ref.height(); ++y)
        for (int x = 0; x < ref.width(); ++x) {
            change =
                std::max(change, double(std::abs(luminance(a.at(x, y)) - luminance(b.at(x, y)))));
            peak = std::max(peak, double(luminance(ref.at(x, y))));
        }
    return peak > 0.0 ? change / peak : 0.0;
}

}  // namespace

// The tail in closed form against Simpson quadrature (both models), and the far share's two
// regimes: 0 when the window covers the object, e^{−σ_tr r}-small a few diffusion lengths out.
TEST(CombinedSplit, FarShareIsTheDipoleTailBetweenSplitRadiusAndObjectExtent) {
    const float eta = 1.3f;
    for (dipole::Model model : {dipole::Model::Dipole, dipole::Model::BetterDipole}) {
        const dipole::ScalarMedium med = dipole::fromReduced(3.f, 1.f, eta);
        const dipole::DipoleProfile p = dipole::DipoleProfile::make(model, med);
        EXPECT_NEAR(p.reflectanceBeyond(0.0), p.totalReflectance(), 1e-12);
        for (double R : {0.1, 0.5, 1.0, 2.0}) {
            const double quad = p.totalReflectance() - dipole::testutil::radialIntegral(p, R);
            // Simpson in r = R u² (200 panels): 1e-6 of the total.
            EXPECT_NEAR(p.reflectanceBeyond(R), quad, 1e-6 * p.totalReflectance()) << R;
        }
        const MaterialSample m = absorbingMaterial();
        const double total = p.totalReflectance();
        EXPECT_NEAR(dipoleFarShare(model, m, eta, 0.5f, 2.f),
                    (p.reflectanceBeyond(0.5) - p.reflectanceBeyond(2.0)) /
                        (total - p.reflectanceBeyond(2.0)),
                    1e-12);
        EXPECT_EQ(dipoleFarShare(model, m, eta, 2.f, 2.f), 0.0);  // r_s = D
        EXPECT_EQ(dipoleFarShare(model, m, eta, 5.f, 2.f), 0.0);  // r_s > D
        EXPECT_EQ(dipoleFarShare(model, m, eta, INF_F, 1e9f), 0.0);
        EXPECT_NEAR(dipoleFarShare(model, m, eta, 0.f, INF_F), 1.0, 1e-12);  // r_s = 0: all
        // Decreasing in r_s, and below e^{−σ_tr(r_s − z_v)}·(1 + σ_tr·z_v) once r_s ≫ z_v.
        double last = 1.0;
        for (float rs = 0.25f; rs < 6.f; rs += 0.25f) {
            const double f = dipoleFarShare(model, m, eta, rs, INF_F);
            EXPECT_LE(f, last);
            last = f;
        }
        EXPECT_LT(dipoleFarShare(model, m, eta, 3.f, INF_F), 1e-4);
        // Optically thin (σt′ = 10⁻⁴ mm⁻¹, D = 35 mm ≪ 1/σt′): R_d is flat over the object, so
        // the share beyond r_s is ≈ 1 − (r_s/D)² of what it holds, however small its total.
        MaterialSample thin;
        thin.sigma_t = Rgb(1e-4f);
        thin.sigma_s = Rgb(0.9e-4f);
        EXPECT_NEAR(dipoleFarShare(model, thin, eta, 5.f, 35.f), 1.0 - 25.0 / 1225.0, 1e-3);
    }
    EXPECT_THROW(
        dipoleFarShare(dipole::Model::Dipole, absorbingMaterial(), eta, std::nanf(""), 1.f),
        ValueError);
    // Painted volumes: the largest share over the voxels (a translucent voxel among absorbing
    // ones decides).
    const Scene s = absorbingSphere();
    MaterialVolume v = *s.objects[0].material;
    const float D = objectExtent(s.objects[0].mesh);
    EXPECT_NEAR(D, 20.f * std::sqrt(3.f), 0.05f);  // the r = 10 mm sphere's box diagonal
    const double absorbing = volumeFarShare(dipole::Model::Dipole, v, s.eta, 2.f, D);
    v.set(Coord(16, 16, 16), skinMaterial());
    const double painted = volumeFarShare(dipole::Model::Dipole, v, s.eta, 2.f, D);
    EXPECT_EQ(painted, dipoleFarShare(dipole::Model::Dipole, skinMaterial(), s.eta, 2.f, D));
    EXPECT_GT(painted, absorbing);
}

namespace {
/// The path-traced subsurface term of `s` (seed 7), the measuring stick of these tests.
reference::ReferenceImage subsurfaceReference(const Scene& s, int spp) {
    reference::ReferenceOptions ro;
    ro.spp = spp;
    ro.subsurfaceOnly = true;
    ro.seed = 7;
    return reference::renderReference(s, ro);
}
}  // namespace

// Fires on an absorbing sphere at the default split (r_s = 4 cells = 5.7 mm ≈ 24 diffusion
// lengths, far share 5·10⁻¹¹): the image is the windowed dipole, bit for bit the skip-off run's
// dipole part. The dipole bounds the light that truly arrives from beyond r_s by the far share
// (dipoleFarShare); what the skip-off image adds there, SSLPV minus its local part, is 18–23 %
// of the peak on this scene: SSLPV's error (its 1.4 mm cells are 6 diffusion lengths), not
// transport. So the skip is checked against a path-traced reference: skip on must be closer.
TEST(CombinedCpu, FarSkipDropsSslpvWhereTheDipoleTailIsNegligible) {
    const Scene s = absorbingSphere();
    const reference::ReferenceImage ref = subsurfaceReference(s, 128);
    const std::vector<uint8_t> mask = bench::maskFromImage(ref.coverage);
    for (SplitMode mode : {SplitMode::Kernel, SplitMode::Steps}) {
        CombinedSettings cs = smallSettings(-1.f, mode);
        const CombinedResult on = renderCombined(s, cs);
        cs.autoSkipSslpv = false;
        const CombinedResult off = renderCombined(s, cs);
        EXPECT_TRUE(on.plan.sslpvSkipped);
        EXPECT_FALSE(on.plan.sslpvOn);
        EXPECT_TRUE(on.plan.dipoleOn);
        EXPECT_LE(on.plan.farShare, double(DEFAULT_FAR_TOLERANCE));
        EXPECT_TRUE(off.plan.sslpvOn && !off.plan.sslpvSkipped);
        EXPECT_EQ(off.plan.farShare, 1.0);  // not evaluated with the switch off
        // Same dipole gather (window and samples): the skip changes only the SSLPV term.
        expectImagesEqual(on.dipole, off.dipole, 0.f, "dipole part");
        expectImagesEqual(on.radiance, off.dipole, 0.f, "skip on = windowed dipole");
        const bench::ErrorReport eOn =
            bench::compareImages(on.radiance, ref.mean, &ref.variance, nullptr, &mask);
        const bench::ErrorReport eOff =
            bench::compareImages(off.radiance, ref.mean, &ref.variance, nullptr, &mask);
        std::printf(
            "absorbing sphere, %s split: far share %.3g, change %.3g of the peak; rel. "
            "RMSE vs %d spp reference (floor %.3f): skip on %.3f, off %.3f\n",
            mode == SplitMode::Kernel ? "kernel" : "steps", on.plan.farShare,
            maxChangeOverPeak(on.radiance, off.radiance, off.radiance), ref.spp,
            eOn.channels[3].relRmseFloor, eOn.channels[3].relRmse, eOff.channels[3].relRmse);
        // Both against the same reference image: its noise (the floor) enters both alike.
        EXPECT_LT(eOn.channels[3].relRmse, eOff.channels[3].relRmse) << int(mode);
    }
}

// Fires because the window covers the object: r_s ≥ D (the box diagonal) leaves SSLPV nothing
// to carry, whatever the material; far share exactly 0, so even tolerance 0 skips. Steps split
// with r_s = 40 mm ≥ D = 34.6 mm and 64 steps (k = 28 < 64: the plan alone keeps SSLPV).
TEST(CombinedCpu, FarSkipDropsSslpvWhenTheWindowCoversTheObject) {
    const Scene s = litSphere();
    CombinedSettings cs = smallSettings(40.f, SplitMode::Steps);
    cs.sslpv.solver.maxSteps = 64;
    cs.farTolerance = 0.f;
    const CombinedResult on = renderCombined(s, cs);
    EXPECT_TRUE(on.plan.sslpvSkipped);
    EXPECT_EQ(on.plan.farShare, 0.0);
    cs.autoSkipSslpv = false;
    const CombinedResult off = renderCombined(s, cs);
    ASSERT_TRUE(off.plan.sslpvOn);
    expectImagesEqual(on.radiance, off.dipole, 0.f, "skip on = windowed dipole");
    // What the skip leaves out is SSLPV's late steps of sources all within r_s: the Steps
    // split's documented overlap (counted twice), not far light.
    std::printf("window covers the sphere: SSLPV late steps held %.3g of the peak\n",
                maxChangeOverPeak(on.radiance, off.radiance, off.radiance));
}

// Does not fire where SSLPV carries light: the skin-like sphere at the default split (far share
// e^{−σ_tr r_s}-large in red, σ_tr = 0.27 mm⁻¹), r_s = 0 (SSLPV alone) or the switch off.
TEST(CombinedCpu, FarSkipKeepsSslpvWhereLightTravelsBeyondTheWindow) {
    const Scene s = litSphere();
    const CombinedResult r = renderCombined(s, smallSettings(-1.f));
    EXPECT_FALSE(r.plan.sslpvSkipped);
    EXPECT_TRUE(r.plan.sslpvOn);
    EXPECT_GT(r.plan.farShare, 0.1);
    const CombinedResult zero = renderCombined(absorbingSphere(), smallSettings(0.f));
    EXPECT_FALSE(zero.plan.sslpvSkipped);
    EXPECT_TRUE(zero.plan.sslpvOn);
    CombinedSettings bad = smallSettings(-1.f);
    bad.farTolerance = -1.f;
    EXPECT_THROW(renderCombined(absorbingSphere(), bad), ValueError);
}

// ---------------------------------------------------------------------------------------------
// Back-lit thin-thick scene against a small path-traced reference

TEST(CombinedCpu, BacklitThinThickCloserToReferenceThanDipoleAlone) {
    const std::string path =
        std::string(LUCENT_SOURCE_DIR) + "/resources/scenes/backlit_thin_thick.json";
    if (!std::filesystem::exists(path))
        GTEST_SKIP() << "scene not found: " << path;
    Scene s = loadScene(path);
    s.camera.width = 48;
    s.camera.height = 36;
    const reference::ReferenceImage ref = subsurfaceReference(s, 96);
    const std::vector<uint8_t> mask = bench::maskFromImage(ref.coverage);

    // SSLPV at grid 64 (64 steps): at grid 32 its thick part is too dark (docs/methods/
    // combined.md); the dipole part without light views (the default: no double count).
    CombinedSettings cs;
    cs.dipole.importanceSamples = 24;
    cs.dipole.uniformSamples = 8;
    cs.sslpv.gridResolution = 64;
    cs.sslpv.solver.maxSteps = 64;
    const CombinedResult comb = renderCombined(s, cs);
    CombinedSettings dOnly = cs;
    dOnly.splitRadius = INF_F;
    dOnly.mode = SplitMode::Steps;  // r_s = ∞: the dipole alone
    dOnly.dipoleLightViews = true;  // the dipole method's default: camera + light views
    const ImageRgb dip = renderCombined(s, dOnly).radiance;
    const bench::ErrorReport ec =
        bench::compareImages(comb.radiance, ref.mean, &ref.variance, nullptr, &mask);
    const bench::ErrorReport ed =
        bench::compareImages(dip, ref.mean, &ref.variance, nullptr, &mask);
    const bench::ChannelError& c = ec.channels[3];
    const bench::ChannelError& d = ed.channels[3];
    std::printf(
        "back-lit thin-thick 48x36, ref %d spp (rel. RMSE floor %.3f): rel. RMSE "
        "combined %.3f, dipole %.3f\n",
        ref.spp, c.relRmseFloor, c.relRmse, d.relRmse);
    // At least 10 % lower relative RMSE. Both are compared with the same reference image, so
    // its noise (floor printed above) enters both alike; the margin guards the method noise.
    EXPECT_LT(c.relRmse, 0.9 * d.relRmse);
}

// ---------------------------------------------------------------------------------------------
// GL provider

namespace {

std::vector<glm::vec4> readRgba(unsigned tex, int w, int h) {
    std::vector<glm::vec4> v(size_t(w) * size_t(h));
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glGetTextureImage(tex, 0, GL_RGBA, GL_FLOAT, GLsizei(v.size() * sizeof(glm::vec4)), v.data());
    return v;  // GL rows, bottom first
}

double imageSum(const ImageRgb& image) {
    double sum = 0.0;
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < image.width(); ++x)
            for (int c = 0; c < 3; ++c)
                sum += double(image.at(x, y)[c]);
    return sum;
}

/// Headless context, renderer and provider (dipole::testutil::GlProviderFixture: skips without
/// EGL, fails on any GL error) with litSphere() at 64×48 loaded into the renderer.
class CombinedGl : public dipole::testutil::GlProviderFixture<CombinedSubsurfaceProvider,
                                                              CombinedProviderSettings> {
protected:
    void SetUp() override {
        GlProviderFixture::SetUp();
        if (IsSkipped())
            return;
        scene = litSphere();
        scene.camera.width = 64;
        scene.camera.height = 48;
        renderer.addMesh(scene.objects[0].mesh);
        renderer.setLights(scene.lights);
        renderer.setCamera(scene.camera);
        gpu::DirectSettings ds;
        ds.subsurfaceOnly = true;
        renderer.setSettings(ds);
    }
    CombinedProviderSettings settings(float rs, SplitMode mode = SplitMode::Kernel) const {
        CombinedProviderSettings ps;
        ps.splitRadius = rs;
        ps.mode = mode;
        ps.eta = scene.eta;
        ps.meshId = 0;
        ps.dipole.samplesPerFrame = 16;
        ps.dipole.maxFrames = 1;
        // The camera image only: the CPU side below rebuilds the gather from it (the dipole
        // provider's light views have their own parity test).
        ps.dipole.lightViews = false;
        ps.sslpv.render.gridResolution = 16;
        ps.sslpv.render.solver.maxSteps = 24;
        return ps;
    }
    ImageRgb frame(const CombinedProviderSettings& ps) {
        provider.setSettings(ps);
        provider.setMesh(scene.objects[0].mesh);
        provider.setLights(scene.lights);
        provider.setMaterial(*scene.objects[0].material, scene.eta);
        renderer.setSubsurfaceProvider(&provider);
        renderer.render();
        return renderer.readRadiance();
    }

    /// The provider's last frame `gl` against the CPU formulas on its own G-buffer.
    void expectOutputMatchesCpuFormulas(const ImageRgb& gl);

    Scene scene;
};

// The provider's output against the CPU formulas evaluated on the G-buffer, irradiance and
// material the GPU rendered: gatherImageSpace (windowed) + SSLPV's exit formula − the local part
// with the provider's kernel (carried to the read-out's albedo with the diffusion part).
// Checked against the parts' own bounds (below).
void CombinedGl::expectOutputMatchesCpuFormulas(const ImageRgb& gl) {
    const SplitPlan plan = provider.stats().plan;
    // CPU side on the GPU's own G-buffer, irradiance and material (as the dipole and SSLPV
    // provider parity tests do).
    const gpu::GBufferView g = renderer.gbuffer();
    const int w = g.width, h = g.height;
    const auto pos = readRgba(g.positionTexture, w, h);
    const auto nrm = readRgba(g.normalTexture, w, h);
    const auto dbg = provider.dipoleProvider().debugTextures();
    const auto E = readRgba(dbg.irradiance, w, h);
    const auto st = readRgba(dbg.sigmaT, w, h);
    const auto ss = readRgba(dbg.sigmaS, w, h);
    dipole::SurfaceBuffers buf;
    buf.resize(w, h);
    buf.clipFromWorld = g.clipFromWorld;
    buf.eye = scene.camera.position;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t gi = size_t(h - 1 - y) * size_t(w) + size_t(x), i = buf.index(x, y);
            if (pos[gi].w == 0.f)
                continue;
            buf.covered[i] = 1;
            buf.position[i] = Point3f(pos[gi]);
            buf.normal[i] = glm::normalize(Normal3f(nrm[gi]));
            buf.irradiance[i] = Rgb(E[gi]);
            buf.material[i] = {Rgb(st[gi]), Rgb(ss[gi]), Rgb(0.f)};
        }
    dipole::GatherSettings gs = provider.dipoleProvider().settings().gatherSettings();
    const ImageRgb cpuDipole = dipole::gatherImageSpace(buf, gs).radiance;
    const CombinedProviderSettings& ps = provider.settings();
    const ImageRgb cpuLhat = localSslpvEstimate(buf, provider.kernel(), plan.splitRadius, ps.eta,
                                                ps.localSamples, ps.dipole.seed);
    const ImageRgb cpuFrac = localSslpvFraction(buf, provider.kernel(), plan.splitRadius,
                                                ps.localSamples, ps.dipole.seed);
    const sslpv::SslpvSolver& solver = provider.sslpvProvider().solver();
    const bool diffusionPart = solver.options().mode == sslpv::SslpvMode::Diffusion;
    const std::shared_ptr<const sslpv::ExactReflectanceRatio> table =
        sslpv::exactReflectanceRatio(scene.eta);
    const KernelSurfaceTerms kernelTerms =
        kernelSurfaceTerms(provider.kernelMaterial(), scene.eta, plan.splitRadius, *table);
    double sumCpu = 0.0, sumGl = 0.0, sumD = 0.0, sumS = 0.0, sumL = 0.0;
    std::vector<double> rel;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = buf.index(x, y);
            if (!buf.covered[i])
                continue;
            const Point3f p = buf.position[i];
            const Normal3f nn = buf.normal[i];
            const Vector3f wo = buf.towardEye(p);
            const float cosO = std::max(0.f, glm::dot(nn, wo));
            const Rgb lpv = solver.exitantRadiance(p, nn, cosO, wo);
            // SSLPV's local part min(s·L̂, f·L_sslpv), s = 1 but with the diffusion part
            // (localScaleToSurfaceMaterial at the albedo its read-out sees and the dipole part's
            // material around x_o).
            const Rgb scale = diffusionPart ? localScaleToSurfaceMaterial(
                                                  solver.readoutAlbedo(p, nn),
                                                  discMeanMaterial(buf, x, y, plan.splitRadius),
                                                  kernelTerms, *table)
                                            : Rgb(1.f);
            const Rgb cpuLocal = glm::min(scale * cpuLhat.at(x, y), cpuFrac.at(x, y) * lpv);
            const float a = luminance(glm::max(cpuDipole.at(x, y) + lpv - cpuLocal, Rgb(0.f))),
                        b = luminance(gl.at(x, y));
            const double partD = luminance(cpuDipole.at(x, y)), partS = luminance(glm::abs(lpv)),
                         partL = luminance(cpuLocal);
            sumCpu += a;
            sumGl += b;
            sumD += partD;
            sumS += partS;
            sumL += partL;
            // L = max(0, D + S − L̂): the clamp is 1-Lipschitz, so |ΔL| ≤ |ΔD| + |ΔS| + |ΔL̂|.
            // Relative to the parts (not to L, which the subtraction can make arbitrarily
            // small): each part's own bound applies.
            if (partD + partS + partL > 0.0)
                rel.push_back(std::abs(double(b) - double(a)) / (partD + partS + partL));
        }
    ASSERT_GT(rel.size(), 500u);
    std::sort(rel.begin(), rel.end());
    std::printf("combined GL/CPU radiance sum %.6f, p95 |GL − CPU| / (D + S + L̂) %.2e\n",
                sumGl / sumCpu, rel[rel.size() * 95 / 100]);
    // The parts' own bounds: dipole provider (image sum 1e-3, p95 1e-4 per pixel;
    // DipoleProvider.FirstFrameMatchesCpuGatherOnALitSphere), SSLPV provider (1e-4·|L| per
    // pixel; SslpvProviderGl), and the local estimate L̂, which uses the same samples in float on
    // both sides (the dipole's argument applies). Since L = max(0, D + S − L̂) and the clamp is
    // 1-Lipschitz, the errors add in absolute terms: |ΔΣL| ≤ 1e-3 (ΣD + ΣL̂) + 1e-4 ΣS, and per
    // pixel |ΔL| ≤ 1e-4 (D + S + L̂) (p95).
    EXPECT_LE(std::abs(sumGl - sumCpu), 1e-3 * (sumD + sumL) + 1e-4 * sumS);
    EXPECT_LT(rel[rel.size() * 95 / 100], 1e-4);
}

}  // namespace

TEST(CombinedProviderSettingsTest, RejectsBadSettingsWithoutGl) {
    CombinedSubsurfaceProvider p;
    CombinedProviderSettings s;
    s.eta = 0.5f;
    EXPECT_THROW(p.setSettings(s), ValueError);
    s = {};
    s.splitRadius = std::nanf("");
    EXPECT_THROW(p.setSettings(s), ValueError);
    s = {};
    s.dipole.samplesPerFrame = 0;
    EXPECT_THROW(p.setSettings(s), ValueError);
    EXPECT_EQ(p.settings().eta, CombinedProviderSettings{}.eta);  // unchanged after a throw
    EXPECT_FALSE(p.isCreated());
}

// With the default (Kernel) split the provider's output equals the CPU formulas evaluated on the
// G-buffer, irradiance and material the GPU rendered: gatherImageSpace (windowed) + SSLPV's
// exit formula − localSslpvEstimate with the provider's kernel.
TEST_F(CombinedGl, OutputIsSumOfPartsAndMatchesCpuFormulasOnItsGBuffer) {
    const ImageRgb gl = frame(settings(-1.f));
    const SplitPlan plan = provider.stats().plan;
    ASSERT_TRUE(plan.dipoleOn && plan.sslpvOn);
    EXPECT_EQ(plan.skipSteps, 2);  // Kernel split: SSLPV's own skip
    EXPECT_EQ(provider.sslpvProvider().solver().options().skipAccumulateSteps, plan.skipSteps);
    ASSERT_FALSE(provider.kernel().ringOuter.empty());
    EXPECT_FLOAT_EQ(provider.dipoleProvider().settings().maxRadius, plan.splitRadius);
    // The kernel is lit as the CPU renderer lights it: at the scene's mean incidence.
    const float incidence = meanIncidenceCosine(scene.objects[0].mesh, scene.lights, scene.eta);
    EXPECT_LT(incidence, 1.f);
    EXPECT_FLOAT_EQ(provider.kernelIncidence(), incidence);
    expectOutputMatchesCpuFormulas(gl);
    // A point light brought close to the sphere's front (a lit cap met at grazing angles
    // towards its rim): the mean incidence changes and the next frame solves the kernel again.
    Light close = scene.lights.front();
    close.type = Light::Type::Point;
    close.position = Point3f(0.f, 0.f, 12.f);
    scene.lights = {close};
    renderer.setLights(scene.lights);
    provider.setLights(scene.lights);
    for (int i = 0; i < 64; ++i) {  // until the parts have settled on the new light
        renderer.render();
        if (provider.stats().converged)
            break;
    }
    EXPECT_TRUE(provider.stats().converged);
    const float moved = meanIncidenceCosine(scene.objects[0].mesh, scene.lights, scene.eta);
    EXPECT_NE(moved, incidence);
    EXPECT_FLOAT_EQ(provider.kernelIncidence(), moved);
    expectOutputMatchesCpuFormulas(renderer.readRadiance());
}

// The same with the diffusion part on a sphere painted darker on one side: the sample pass
// writes the albedo its read-out sees, and the add pass carries L̂ to it as the CPU renderer does
// (localScaleToSurfaceMaterial; docs/methods/combined.md, "The kernel at the painted surface").
TEST_F(CombinedGl, DiffusionPartCarriesTheKernelToThePaintedSurface) {
    MaterialVolume& vol = *scene.objects[0].material;
    const MaterialSample dark = darkerSkin();
    paintHalfAbove(vol, dark);
    (void)vol.takeDirtyBricks();
    CombinedProviderSettings ps = settings(-1.f);
    ps.sslpv.render.solver.mode = sslpv::SslpvMode::Diffusion;
    ps.sslpv.render.solver.maxSteps = 1024;
    ps.sslpv.render.solver.stopEpsilon = 1e-3f;
    const ImageRgb gl = frame(ps);
    ASSERT_TRUE(provider.stats().plan.dipoleOn && provider.stats().plan.sslpvOn);
    // Both halves' albedos are read, and the kernel's lies between them: the scale is not 1.
    const sslpv::SslpvSolver& solver = provider.sslpvProvider().solver();
    const Rgb kernelAlbedo = reducedAlbedo(provider.kernelMaterial());
    EXPECT_LT(kernelAlbedo.b, reducedAlbedo(skinMaterial()).b - 0.01f);
    EXPECT_GT(kernelAlbedo.b, reducedAlbedo(dark).b + 0.01f);
    const Vector3f toCamera = glm::normalize(scene.camera.position);
    const Normal3f n0 = glm::normalize(Normal3f(-1.f, 0.f, 0.f) + toCamera);
    const Normal3f n1 = glm::normalize(Normal3f(1.f, 0.f, 0.f) + toCamera);
    EXPECT_GT(solver.readoutAlbedo(Point3f(10.f * n0), n0).b, kernelAlbedo.b);
    EXPECT_LT(solver.readoutAlbedo(Point3f(10.f * n1), n1).b, kernelAlbedo.b);
    expectOutputMatchesCpuFormulas(gl);
}

TEST_F(CombinedGl, LimitsSelectOnePartAndMaterialSyncReachesBoth) {
    const ImageRgb lpvOnly = frame(settings(0.f));
    EXPECT_FALSE(provider.stats().plan.dipoleOn);
    const ImageRgb dipOnly = frame(settings(INF_F, SplitMode::Steps));
    EXPECT_FALSE(provider.stats().plan.sslpvOn);
    EXPECT_EQ(provider.dipoleProvider().settings().maxRadius, 0.f);
    double sl = 0, sd = 0;
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x) {
            sl += luminance(lpvOnly.at(x, y));
            sd += luminance(dipOnly.at(x, y));
        }
    EXPECT_GT(sl, 0.0);
    EXPECT_GT(sd, 0.0);

    // Painting: the dirty bricks are taken once and reach both parts.
    (void)frame(settings(-1.f));
    const int resetsBefore = provider.stats().dipole.resets;
    const int incBefore = provider.stats().sslpv.incrementalUpdates;
    MaterialVolume& vol = *scene.objects[0].material;
    MaterialSample darker = skinMaterial();
    darker.sigma_t = darker.sigma_s + Rgb(1.f);
    vol.set(Coord(16, 16, 28), darker);
    const size_t taken = provider.syncMaterial(vol);
    EXPECT_GE(taken, 1u);
    EXPECT_TRUE(vol.takeDirtyBricks().empty());
    renderer.render();
    EXPECT_EQ(provider.stats().sslpv.incrementalUpdates, incBefore + 1);
    EXPECT_GT(provider.stats().dipole.resets, resetsBefore);
    EXPECT_GE(provider.stats().dipole.lastUploadBricks, 1);
}

// The provider's automatic skip on the absorbing sphere: SSLPV, the kernel and the local
// estimate are left out, so the frame is the windowed dipole alone, bit for bit a fresh provider
// with the Steps split whose plan leaves SSLPV out (k = 4 ≥ 3 steps) at the same r_s and dipole
// samples. A stroke that paints a translucent voxel brings SSLPV back (the far share is taken
// over the whole volume).
TEST_F(CombinedGl, FarSkipLeavesSslpvOutUntilAStrokeNeedsIt) {
    scene.objects[0].material =
        std::make_shared<MaterialVolume>(scene.objects[0].material->spec(), absorbingMaterial());
    const ImageRgb skipped = frame(settings(-1.f));
    ASSERT_TRUE(provider.stats().plan.sslpvSkipped);
    EXPECT_FALSE(provider.stats().plan.sslpvOn);
    EXPECT_EQ(provider.stats().localEstimates, 0);
    // No kernel to wait for: converged with the dipole's one frame (renderers stop there).
    EXPECT_TRUE(provider.stats().converged);
    // The same first frame of a fresh provider (the dipole's progressive state starts alike).
    CombinedProviderSettings dipoleOnly =
        settings(provider.stats().plan.splitRadius, SplitMode::Steps);
    dipoleOnly.sslpv.render.solver.maxSteps = 3;
    dipoleOnly.autoSkipSslpv = false;
    CombinedSubsurfaceProvider fresh;
    fresh.create();
    fresh.setSettings(dipoleOnly);
    fresh.setMesh(scene.objects[0].mesh);
    fresh.setLights(scene.lights);
    fresh.setMaterial(*scene.objects[0].material, scene.eta);
    renderer.setSubsurfaceProvider(&fresh);
    renderer.render();
    const ImageRgb windowed = renderer.readRadiance();
    ASSERT_FALSE(fresh.stats().plan.sslpvOn);
    ASSERT_FALSE(fresh.stats().plan.sslpvSkipped);
    renderer.setSubsurfaceProvider(&provider);
    fresh.destroy();
    expectImagesEqual(skipped, windowed, 0.f, "GL skip on = windowed dipole");
    CombinedProviderSettings off = settings(-1.f);
    off.autoSkipSslpv = false;
    (void)frame(off);
    EXPECT_TRUE(provider.stats().plan.sslpvOn);

    (void)frame(settings(-1.f));
    ASSERT_TRUE(provider.stats().plan.sslpvSkipped);
    MaterialVolume& vol = *scene.objects[0].material;
    vol.set(Coord(16, 16, 28), skinMaterial());
    ASSERT_GE(provider.syncMaterial(vol), 1u);
    EXPECT_TRUE(provider.stats().plan.sslpvOn);
    EXPECT_FALSE(provider.stats().plan.sslpvSkipped);
    EXPECT_GT(provider.stats().plan.farShare, double(DEFAULT_FAR_TOLERANCE));
    const int before = provider.stats().localEstimates;
    renderer.render();
    EXPECT_GT(provider.stats().localEstimates, before);  // the Kernel split runs again in full
}

// A paint stroke changes only the material. The local SSLPV estimate L̂ (32 samples per pixel of
// the irradiance image and the kernel) does not depend on it, so the stroke frame reuses it; the
// kernel (mean material, a half-space SSLPV solve) is recomputed at the next frame, and only
// then does the provider report convergence. The converged image equals the one rendered from
// scratch with the painted material: the same dipole samples, SSLPV resampled incrementally
// (bit-identical to a full resample) and the same kernel; 1e-5 relative allows for float
// summation order only.
// A stroke that hardly moves the volume's mean material keeps the kernel and L̂ (the 57-ms
// local estimate at 640×360 on llvmpipe): KERNEL_MATERIAL_TOLERANCE, 1 % of σa and σs′ per
// channel. What that costs in the answer, against a render from scratch (which computes the
// kernel for the new mean): over the object's pixels, the median and 95th percentile of the
// relative luminance difference (the dipole part's restarted pixels differ by their own Monte
// Carlo noise, at most a few per cent of the pixels: the percentile leaves them out).
TEST_F(CombinedGl, SmallStrokeKeepsTheKernelWithinItsTolerance) {
    (void)frame(settings(-1.f));
    for (int i = 0; i < 20 && !provider.stats().converged; ++i)
        renderer.render();
    ASSERT_TRUE(provider.stats().converged);
    const int estimates = provider.stats().localEstimates;
    const SslpvSurfaceKernel before = provider.kernel();
    MaterialVolume& vol = *scene.objects[0].material;
    const std::vector<Coord> shell = surfaceShell(vol, before.cellSize);
    const MaterialSample surfaceBefore = surfaceMaterial(vol, shell);
    // Twice the absorption in a 3×3×4 block under the front: the surface cells' mean σa moves by
    // under the 1 % tolerance.
    MaterialSample denser = skinMaterial();
    denser.sigma_t = denser.sigma_s + 2.f * (denser.sigma_t - denser.sigma_s);
    for (int z = 28; z < 32; ++z)
        for (int y = 15; y < 18; ++y)
            for (int x = 15; x < 18; ++x)
                vol.set(Coord(x, y, z), denser);
    ASSERT_TRUE(kernelMaterialClose(surfaceMaterial(vol, shell), surfaceBefore));
    ASSERT_GE(provider.syncMaterial(vol), 1u);
    for (int i = 0; i < 20 && (i < 2 || !provider.stats().converged); ++i)
        renderer.render();
    ASSERT_TRUE(provider.stats().converged);
    EXPECT_EQ(provider.stats().kernelsKept, 1);
    EXPECT_EQ(provider.stats().localEstimates, estimates);
    EXPECT_EQ(provider.kernel().ringValue, before.ringValue);
    const ImageRgb incremental = renderer.readRadiance();
    (void)frame(
        settings(-1.f));  // setMaterial: everything from scratch, the kernel for the new mean
    for (int i = 0; i < 20 && !provider.stats().converged; ++i)
        renderer.render();
    EXPECT_NE(provider.kernel().ringValue, before.ringValue);
    const ImageRgb scratch = renderer.readRadiance();
    float peak = 0.f;
    for (int y = 0; y < scratch.height(); ++y)
        for (int x = 0; x < scratch.width(); ++x)
            peak = std::max(peak, luminance(scratch.at(x, y)));
    std::vector<float> rel;
    for (int y = 0; y < scratch.height(); ++y)
        for (int x = 0; x < scratch.width(); ++x) {
            const float ref = luminance(scratch.at(x, y));
            if (ref > 0.01f * peak)
                rel.push_back(std::abs(luminance(incremental.at(x, y)) - ref) / ref);
        }
    ASSERT_GT(rel.size(), 100u);
    std::sort(rel.begin(), rel.end());
    const float median = rel[rel.size() / 2], p95 = rel[rel.size() * 95 / 100];
    std::printf("kernel kept: relative difference to a fresh kernel, median %.2g, p95 %.2g\n",
                double(median), double(p95));
    // The kernel's part of a pixel is L̂ ≤ its near share of SSLPV's radiance; a 1 % move of
    // the mean's coefficients moves the kernel's rings by about as much, so the pixel moves by
    // well under 1 %.
    EXPECT_LT(p95, 0.01f);
}

TEST_F(CombinedGl, StrokeReusesLocalEstimateAndDefersKernel) {
    (void)frame(settings(-1.f));
    for (int i = 0; i < 20 && !provider.stats().converged; ++i)
        renderer.render();
    ASSERT_TRUE(provider.stats().converged);  // maxFrames = 1
    EXPECT_EQ(provider.stats().localEstimates, 1);
    renderer.render();  // nothing changed: nothing recomputed
    EXPECT_EQ(provider.stats().localEstimates, 1);

    MaterialVolume& vol = *scene.objects[0].material;
    const std::vector<Coord> shell = surfaceShell(vol, provider.kernel().cellSize);
    const MaterialSample surfaceBefore = surfaceMaterial(vol, shell);
    MaterialSample darker = skinMaterial();
    darker.sigma_t = darker.sigma_s + Rgb(1.f);
    // A 4×4 patch of the front, 8 voxels deep: it reaches the surface cells the kernel's
    // material is taken from (surfaceShell) and moves their mean well past the tolerance.
    for (int z = 24; z < 32; ++z)
        for (int y = 14; y < 18; ++y)
            for (int x = 14; x < 18; ++x)
                vol.set(Coord(x, y, z), darker);
    ASSERT_FALSE(kernelMaterialClose(surfaceMaterial(vol, shell), surfaceBefore));
    const SslpvSurfaceKernel before = provider.kernel();
    ASSERT_GE(provider.syncMaterial(vol), 1u);
    renderer.render();  // the stroke frame: old kernel, old L̂
    EXPECT_EQ(provider.stats().localEstimates, 1);
    EXPECT_FALSE(provider.stats().converged);  // the kernel is still to be updated
    EXPECT_EQ(provider.kernel().ringValue, before.ringValue);
    renderer.render();  // the kernel follows the mean material, and L̂ with it
    EXPECT_EQ(provider.stats().localEstimates, 2);
    EXPECT_NE(provider.kernel().ringValue, before.ringValue);
    for (int i = 0; i < 20 && !provider.stats().converged; ++i)
        renderer.render();
    ASSERT_TRUE(provider.stats().converged);
    EXPECT_EQ(provider.stats().localEstimates, 2);
    const ImageRgb incremental = renderer.readRadiance();
    // The dipole part restarted only the pixels whose material changed (material-only
    // restarts, docs/methods/dipole.md §3c); they caught up with samples of their own stream.
    const int restarted = provider.stats().dipole.pixelsRestarted;
    EXPECT_GT(restarted, 0);

    (void)frame(settings(-1.f));  // setMaterial: everything from scratch
    for (int i = 0; i < 20 && !provider.stats().converged; ++i)
        renderer.render();  // past the dipole part's interactive preview frame
    const ImageRgb scratch = renderer.readRadiance();
    // Every other pixel (SSLPV, the kernel, L̂ and the dipole's kept sums) equals the render
    // from scratch; the restarted ones agree within their Monte Carlo noise (z-score of the
    // mean difference; per-pixel errors are independent).
    int differing = 0;
    double sum = 0.0, sum2 = 0.0;
    for (int y = 0; y < scratch.height(); ++y)
        for (int x = 0; x < scratch.width(); ++x) {
            bool same = true;
            for (int c = 0; c < 3; ++c)
                same = same && std::abs(incremental.at(x, y)[c] - scratch.at(x, y)[c]) <=
                                   1e-5f * std::abs(scratch.at(x, y)[c]);
            if (same)
                continue;
            ++differing;
            const double d = double(luminance(incremental.at(x, y))) - luminance(scratch.at(x, y));
            sum += d;
            sum2 += d * d;
        }
    std::printf("stroke vs from scratch: %d pixels differ (%d restarted by the dipole part)\n",
                differing, restarted);
    EXPECT_LE(differing, restarted);
    if (differing >= 10) {
        const double n = double(differing), mean = sum / n;
        const double sd = std::sqrt(std::max(sum2 / n - mean * mean, 0.0));
        EXPECT_LT(std::abs(mean) / (sd / std::sqrt(n)), 4.0);
    }
}

// Live refinement of the SSLPV part (SslpvProviderOptions::refineSteps): in a high-albedo
// medium 24 steps leave light in flight, so the provider is not converged after the first
// frame; idle frames carry the propagation on, and the picture they end with is the one a single
// solve of as many steps gives, pixel for pixel: the SSLPV grid (continuePropagation is that
// solve's steps), the kernel (computed for the refined solve from the start) and L̂ with it.
TEST_F(CombinedGl, SslpvPartRefinesOverIdleFramesToOneLongerSolve) {
    MaterialVolume& volume = *scene.objects[0].material;
    MaterialVolume marble(volume.spec(), findPreset("marble").sample());
    marble.setInsideMask(volume.insideMask());
    marble.setEta(volume.eta());
    volume = std::move(marble);

    CombinedProviderSettings live = settings(-1.f);
    live.sslpv.render.solver.brickStopEpsilon = 1e-4f;  // the live preview's stop rules
    live.sslpv.refineSteps = 480;
    const double first = imageSum(frame(live));
    EXPECT_FALSE(provider.stats().converged) << "marble keeps light in flight after 24 steps";
    int frames = 1;
    while (!provider.stats().converged) {
        renderer.render();
        ASSERT_LT(++frames, 64);
    }
    const int refinements = provider.stats().sslpv.refinements;
    EXPECT_GT(refinements, 0);
    const int stepsUsed = provider.sslpvProvider().solver().stats().stepsUsed;
    EXPECT_GT(stepsUsed, 24);
    const ImageRgb refined = renderer.readRadiance();
    const std::vector<Rgb> kernel = provider.kernel().ringValue;

    CombinedProviderSettings once = live;  // one solve with the bound the refinement had
    once.sslpv.refineSteps = 0;
    once.sslpv.render.solver.maxSteps = live.sslpv.refineSteps;
    (void)frame(once);
    for (int i = 0; i < 20 && !provider.stats().converged; ++i)
        renderer.render();
    ASSERT_TRUE(provider.stats().converged);
    EXPECT_EQ(provider.stats().sslpv.refinements, refinements) << "one solve, no refinement";
    EXPECT_EQ(provider.sslpvProvider().solver().stats().stepsUsed, stepsUsed);
    EXPECT_EQ(provider.kernel().ringValue, kernel);
    const ImageRgb expected = renderer.readRadiance();
    EXPECT_TRUE(refined.pixels() == expected.pixels()) << "not the longer solve's image";
    const double refinedSum = imageSum(refined);
    std::printf(
        "combined, marble sphere: first frame %.4f of the refined one after %d frames "
        "(%d SSLPV steps)\n",
        first / refinedSum, frames, stepsUsed);
    EXPECT_LT(first, 0.99 * refinedSum) << "24 steps should leave light in flight here";
}
