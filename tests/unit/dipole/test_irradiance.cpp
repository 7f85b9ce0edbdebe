// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/dipole/IrradiancePass.h>
#include <lucent/mesh/Procedural.h>

#include "DipoleTestUtil.h"

#include <gtest/gtest.h>

#include <memory>

using namespace lucent;
using namespace lucent::dipole;
using namespace lucent::dipole::testutil;

namespace {

MaterialSample slabMaterial() {
    MaterialSample m;
    m.sigma_s = Rgb(2.f, 1.f, 0.5f);
    m.sigma_t = m.sigma_s + Rgb(0.05f, 0.1f, 0.2f);
    return m;
}

/// A 40×30×10 mm box; an orthographic camera looks straight down at its +z face (z = 5 mm)
/// with 0.1 mm pixels; a directional light shines straight down with 1 W/mm².
Scene slabScene() {
    return testutil::boxScene(slabMaterial(),
                              {.size = {40.f, 30.f, 10.f}, .viewHeight = 12.f, .pixels = 120});
}

}  // namespace

TEST(IrradiancePass, PointLightIrradianceFollowsEq5) {
    Light l;
    l.type = Light::Type::Point;
    l.position = {0.f, 3.f, 4.f};  // 5 mm away, cos θ = 0.8
    l.intensity = Rgb(25.f);       // W/sr
    const Rgb e = lightIrradiance(l, Point3f(0.f), Normal3f(0.f, 0.f, 1.f), 1.5f);
    const float ft = float(1.0 - fresnelDielectric(0.8, 1.5));
    EXPECT_NEAR(e.r, ft * 25.f * 0.8f / 25.f, 1e-6f);
    l.position = {0.f, 0.f, -4.f};  // behind the surface
    EXPECT_EQ(lightIrradiance(l, Point3f(0.f), Normal3f(0.f, 0.f, 1.f), 1.5f), Rgb(0.f));
}

TEST(IrradiancePass, SlabFaceMatchesExactIntegral) {
    const Scene scene = slabScene();
    const SurfaceBuffers buf = buildSurfaceBuffers(scene);
    const float ft = float(1.0 - fresnelDielectric(1.0, 1.3));
    for (size_t i = 0; i < buf.covered.size(); ++i) {
        ASSERT_TRUE(buf.covered[i]);
        ASSERT_NEAR(buf.position[i].z, 5.f, 1e-4f);
        ASSERT_NEAR(buf.irradiance[i].g, ft, 1e-6f);
        ASSERT_EQ(buf.material[i], slabMaterial());
    }
    GatherSettings gs;
    gs.importanceSamples = 24;
    gs.uniformSamples = 8;
    const GatherResult g = renderImageSpaceDipole(scene, gs);
    // The gather sees only the 12 × 12 mm in view: B = F_t · ∫_view R_d dA.
    for (int c = 0; c < 3; ++c) {
        const MaterialSample m = slabMaterial();
        const DipoleProfile p =
            DipoleProfile::jensen(m.sigma_t[c] - m.sigma_s[c], m.sigma_s[c], 1.3);
        expectUnbiased(
            g, buf, block(58, 58, 4, 4),
            [&](glm::dvec2 xo, int) { return ft * exactBox(p, xo, -6, 6, -6, 6); }, c);
    }
}

TEST(IrradiancePass, SelfShadowAndMisses) {
    Scene scene = slabScene();
    scene.camera.orthoHeight = 60.f;  // the box now covers only the middle of the picture
    // Light from below: the top face is in shadow of the box itself.
    scene.lights[0].direction = {0.f, 0.f, 1.f};
    const SurfaceBuffers buf = buildSurfaceBuffers(scene);
    EXPECT_FALSE(buf.covered[buf.index(0, 0)]);
    EXPECT_TRUE(buf.covered[buf.index(60, 60)]);
    EXPECT_EQ(buf.irradiance[buf.index(60, 60)], Rgb(0.f));
    // A point light above one corner: the top face is lit, a shadow ray never self-hits.
    scene.lights[0].type = Light::Type::Point;
    scene.lights[0].position = {0.f, 0.f, 30.f};
    scene.lights[0].intensity = Rgb(100.f);
    const SurfaceBuffers lit = buildSurfaceBuffers(scene);
    EXPECT_GT(lit.irradiance[lit.index(60, 60)].r, 0.f);
    Scene empty;
    EXPECT_THROW(buildSurfaceBuffers(empty), ValueError);
}
