// SPDX-License-Identifier: MIT
// Light-view irradiance images for the image-space dipole (Mertens et al. 2005 §7.1): the balance
// heuristic over the camera and light images, "through" transport of thin parts, the skip
// criterion and the scene-level pass (buildLightViewBuffers / renderImageSpaceDipole).
#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/dipole/ImageSpace.h>
#include <lucent/dipole/IrradiancePass.h>
#include <lucent/mesh/Procedural.h>

#include "DipoleTestUtil.h"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>

using namespace lucent;
using namespace lucent::dipole;
using namespace lucent::dipole::testutil;

namespace {

MaterialSample rgbMaterial() {
    MaterialSample m;
    m.sigma_s = Rgb(2.f, 1.f, 0.5f);                 // σs′, mm⁻¹
    m.sigma_t = m.sigma_s + Rgb(0.05f, 0.1f, 0.2f);  // + σa
    return m;
}

/// Half extents (mm) of the lit rectangle every view below covers.
constexpr double HX = 8.0, HY = 6.0;

/// An orthographic view along unit `dir` of the plane z = `z` (outward normal `n`, ±z),
/// `w`×`h` pixels spanning `extent`×`extent`·h/w mm; a pixel is covered where its ray meets the
/// plane inside [−HX, HX]×[−HY, HY]; there E = `irradiance`.
SurfaceBuffers orthoView(Vector3f dir, float z, Normal3f n, int w, int h, float extent,
                         float irradiance) {
    dir = glm::normalize(dir);
    SurfaceBuffers b;
    b.resize(w, h);
    const Point3f centre(0.f, 0.f, z);
    const Vector3f up = std::abs(dir.y) < 0.9f ? Vector3f(0, 1, 0) : Vector3f(1, 0, 0);
    const float hw = 0.5f * extent, hh = hw * float(h) / float(w);
    b.clipFromWorld =
        glm::ortho(-hw, hw, -hh, hh, 0.1f, 200.f) * glm::lookAt(centre - 50.f * dir, centre, up);
    b.orthographic = true;
    b.viewDirection = dir;
    const Mat4f worldFromClip = glm::inverse(b.clipFromWorld);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::vec4 ndc((x + 0.5f) / float(w) * 2.f - 1.f,
                                1.f - (y + 0.5f) / float(h) * 2.f, -1.f, 1.f);
            const glm::vec4 o4 = worldFromClip * ndc;
            const Point3f o = Point3f(o4) / o4.w;
            const float t = (z - o.z) / dir.z;
            const Point3f p = o + t * dir;
            if (std::abs(p.x) > HX || std::abs(p.y) > HY)
                continue;
            const size_t i = b.index(x, y);
            b.position[i] = p;
            b.normal[i] = n;
            b.covered[i] = 1;
            b.material[i] = rgbMaterial();
            b.irradiance[i] = Rgb(irradiance);
        }
    return b;
}

DipoleProfile channelProfile(int c) {
    const MaterialSample m = rgbMaterial();
    return DipoleProfile::jensen(m.sigma_t[c] - m.sigma_s[c], m.sigma_s[c], 1.3);
}

GatherSettings settings() {
    GatherSettings gs;
    gs.importanceSamples = 24;
    gs.uniformSamples = 8;
    return gs;
}

/// The camera: straight down at z = 0 with 0.1 mm pixels, 160×120 (exactly the lit rectangle).
SurfaceBuffers camera(float irradiance) {
    return orthoView({0, 0, -1}, 0.f, {0, 0, 1}, 160, 120, 16.f, irradiance);
}

}  // namespace

TEST(LightView, BalanceHeuristicDoesNotCountAPointTwice) {
    // Camera and an oblique light view (35° from the normal) both see the whole lit plane. Every
    // surface point is reachable through both images; if the weights did not sum to one the
    // result would be up to twice the exact ∫ R_d dA over the rectangle.
    const SurfaceBuffers cam = camera(1.f);
    const float s = std::sin(0.61f), c = std::cos(0.61f);
    const SurfaceBuffers light = orthoView({0, s, -c}, 0.f, {0, 0, 1}, 220, 220, 22.f, 1.f);
    const GatherResult g = gatherImageSpace(cam, {light}, settings());
    EXPECT_EQ(g.stats.lightViews, 1);
    for (int ch = 0; ch < 3; ++ch) {
        const DipoleProfile p = channelProfile(ch);
        expectUnbiased(
            g, cam, block(78, 58, 4, 4),
            [&](glm::dvec2 xo, int) { return exactBox(p, xo, -HX, HX, -HY, HY); }, ch);
    }
    // The light view adds no lit surface the camera cannot see: the skip criterion is 0.
    EXPECT_EQ(backlitFluxFraction(cam, light, settings()), 0.0);
}

TEST(LightView, ThinSlabLitFromBehindTransmitsThroughTheLightImage) {
    // A 1 mm slab: the camera sees the unlit front face z = 0; a light below sees the back face
    // z = −1 mm with E = 1. The gather reaches x_i on the back face through the light image and
    // weights it by R_d(|x_o − x_i|), the 3-D distance: B(x_o) = ∫ R_d(√(ρ² + T²)) dA over the
    // back face, i.e. exactBox with radii mapped ρ → √(ρ² + T²).
    const double T = 1.0;
    const SurfaceBuffers cam = camera(0.f);
    const SurfaceBuffers light = orthoView({0, 0, 1}, -float(T), {0, 0, -1}, 200, 150, 20.f, 1.f);
    const GatherResult camOnly = gatherImageSpace(cam, settings());
    EXPECT_EQ(camOnly.exitance.at(80, 60), Rgb(0.f));  // the published method sees nothing
    const GatherResult g = gatherImageSpace(cam, {light}, settings());
    for (int ch = 0; ch < 3; ++ch) {
        const DipoleProfile p = channelProfile(ch);
        const auto through = [&](glm::dvec2 xo, int) {
            // Polar rays from x_o as exactBox, each radial interval [t0, t1] of the back face
            // contributes ∫ R_d(√(ρ²+T²)) 2πρ dρ = ∫_{√(t0²+T²)}^{√(t1²+T²)} R_d(s) 2πs ds.
            const int rays = 2000;
            double sum = 0.0;
            for (int k = 0; k < rays; ++k) {
                const double phi = 2 * M_PI * (k + 0.5) / rays;
                const glm::dvec2 d(std::cos(phi), std::sin(phi));
                double t1 = 1e30;
                const double lo[2] = {-HX, -HY}, hi[2] = {HX, HY};
                for (int a = 0; a < 2; ++a) {
                    if (std::abs(d[a]) < 1e-15)
                        continue;
                    const double ta = (lo[a] - xo[a]) / d[a], tb = (hi[a] - xo[a]) / d[a];
                    t1 = std::min(t1, std::max(ta, tb));
                }
                sum += radialIntegral(p, std::sqrt(t1 * t1 + T * T)) - radialIntegral(p, T);
            }
            return sum / rays;
        };
        expectUnbiased(g, cam, block(78, 58, 4, 4), through, ch);
    }
    // Every lit texel lies 1 mm behind a camera-visible point, within R′: fully back-lit.
    EXPECT_GT(backlitFluxFraction(cam, light, settings()), 0.99);
    // A mismatched light view is a clear error naming it.
    SurfaceBuffers broken = light;
    broken.irradiance.pop_back();
    EXPECT_THROW(gatherImageSpace(cam, {broken}, settings()), ValueError);
}

namespace {

/// A 30×30×`thickness` mm slab (faces z = ±thickness/2) with a directional light from below
/// and an orthographic camera from above (0.1 mm pixels, 10×10 mm in view).
Scene backlitSlab(float thickness) {
    // The light travels up (+z): it lights the bottom face.
    return testutil::boxScene(
        rgbMaterial(),
        {.size = {30.f, 30.f, thickness}, .grid = 64, .lightDirection = {0.f, 0.f, 1.f}});
}

}  // namespace

TEST(LightView, SceneLevelBackLitSlab) {
    const float T = 1.f;
    const Scene scene = backlitSlab(T);
    // The light view: orthographic along the light, the bottom face lit with F_t(0)·1 W/mm².
    const SurfaceBuffers light = buildLightViewBuffers(scene, 0, 128);
    EXPECT_TRUE(light.orthographic);
    const size_t centre = light.index(64, 64);
    ASSERT_TRUE(light.covered[centre]);
    const float ft = float(1.0 - fresnelDielectric(1.0, 1.3));
    EXPECT_NEAR(light.position[centre].z, -0.5f * T, 1e-4f);
    EXPECT_NEAR(light.irradiance[centre].g, ft, 1e-6f);

    std::vector<LightViewReport> reports;
    const GatherResult g = renderImageSpaceDipole(scene, settings(), {}, &reports);
    ASSERT_EQ(reports.size(), 1u);
    EXPECT_TRUE(reports[0].built);
    EXPECT_TRUE(reports[0].used);
    // The 10×10 mm in view of the 30×30 mm lit face: 1/9 of the flux is behind visible pixels.
    EXPECT_NEAR(reports[0].backlitFraction, 1.0 / 9.0, 0.02);
    EXPECT_EQ(g.stats.lightViews, 1);
    // The centre: the bottom face is (nearly) a half-space 1 mm below: B ≈ F_t ∫ R_d(√(ρ²+T²))
    // dA (the 30 mm face's edges are ≥ 15 mm away, beyond R′ of the reddest channel here).
    const SurfaceBuffers cam = buildSurfaceBuffers(scene);
    for (int ch = 0; ch < 3; ++ch) {
        const DipoleProfile p = channelProfile(ch);
        const double exact = ft * (radialIntegral(p, 15.0) - radialIntegral(p, T));
        expectUnbiased(
            g, cam, block(48, 48, 4, 4), [&](glm::dvec2, int) { return exact; }, ch);
    }
    // Disabled light views: the published camera-only method, dark.
    LightViewSettings off;
    off.enabled = false;
    const GatherResult dark = renderImageSpaceDipole(scene, settings(), off, &reports);
    EXPECT_FALSE(reports[0].built);
    EXPECT_EQ(dark.exitance.at(50, 50), Rgb(0.f));
    // Front-lit: the light sees only what the camera sees, so its view is skipped.
    Scene front = scene;
    front.lights[0].direction = {0.f, 0.f, -1.f};
    front.camera.orthoHeight = 40.f;  // the whole top face in view
    renderImageSpaceDipole(front, settings(), {}, &reports);
    EXPECT_TRUE(reports[0].built);
    EXPECT_FALSE(reports[0].used);
    EXPECT_LT(reports[0].backlitFraction, 1e-3);
    // A point light inside the bounding sphere cannot frame the object: not built, explained.
    Scene inside = scene;
    inside.lights[0].type = Light::Type::Point;
    inside.lights[0].position = {0.f, 0.f, 0.f};
    EXPECT_THROW(buildLightViewBuffers(inside, 0, 64), ValueError);
    LightViewSettings bad;
    bad.resolution = 8;
    EXPECT_THROW(renderImageSpaceDipole(scene, settings(), bad), ValueError);
}

TEST(LightView, SkippedFrontLitViewChangesNothingButTheWork) {
    // The light-view skip (LightViewSettings::threshold, docs/benchmarks.md "Skips") on a
    // front-lit slab whose whole lit face the camera sees: the view adds no surface the camera
    // misses (back-lit fraction 0), so gathering it (gatherAll) has the same expectation (the
    // balance heuristic over images counts each point once); skipping it leaves exactly the
    // camera-only gather. Both are checked against the half-space value F_t ∫₀^15mm R_d dA
    // (the face's edges are ≥ 15 mm from the centre, beyond R′ of the reddest channel).
    Scene front = backlitSlab(1.f);
    front.lights[0].direction = {0.f, 0.f, -1.f};
    front.camera.orthoHeight = 40.f;
    std::vector<LightViewReport> reports;
    const GatherResult skipped = renderImageSpaceDipole(front, settings(), {}, &reports);
    ASSERT_EQ(reports.size(), 1u);
    EXPECT_TRUE(reports[0].built);
    EXPECT_FALSE(reports[0].used) << "the skip did not fire";
    EXPECT_EQ(skipped.stats.lightViews, 0);
    LightViewSettings all;
    all.gatherAll = true;
    const GatherResult gathered = renderImageSpaceDipole(front, settings(), all, &reports);
    EXPECT_TRUE(reports[0].used);
    EXPECT_EQ(gathered.stats.lightViews, 1);
    LightViewSettings off;
    off.enabled = false;
    const GatherResult cameraOnly = renderImageSpaceDipole(front, settings(), off);
    EXPECT_EQ(skipped.exitance.pixels(), cameraOnly.exitance.pixels());  // exact: same estimator
    const SurfaceBuffers cam = buildSurfaceBuffers(front);
    const float ft = float(1.0 - fresnelDielectric(1.0, 1.3));
    for (int ch = 0; ch < 3; ++ch) {
        const DipoleProfile p = channelProfile(ch);
        const double exact = ft * radialIntegral(p, 15.0);
        const auto value = [&](glm::dvec2, int) { return exact; };
        expectUnbiased(skipped, cam, block(46, 46, 8, 8), value, ch);
        expectUnbiased(gathered, cam, block(46, 46, 8, 8), value, ch);
    }
}
