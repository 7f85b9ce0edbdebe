// SPDX-License-Identifier: MIT
/// @file
/// @brief The light skip changes time, not the answer (issue 15, item 3): renderImage with the
/// skip on and off (RenderOptions::lightSkipEpsilon < 0) on a scene with a spot aimed away from
/// the object and a point light below ε of the key light.
/// - A spot whose cone misses the object adds exactly zero: the images are bitwise equal.
/// - A light skipped for being dim adds its own image (the methods are linear in the lights):
///   at most ε × (the key light's image on a surface of the same orientation), so every pixel
///   moves by at most ε of the image's largest value.
/// - The reference path tracer never skips.

#include <lucent/core/Image.h>
#include <lucent/methods/RenderImage.h>
#include <lucent/scene/LightReach.h>
#include <lucent/scene/SceneFile.h>

#include "GlTestContext.h"
#include "ImageTestUtil.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace lucent::methods {
namespace {

Scene skinSphere() {
    Scene scene = loadScene(std::string(LUCENT_SOURCE_DIR) + "/resources/scenes/skin_sphere.json");
    scene.camera.width = 48;
    scene.camera.height = 40;
    return scene;
}

/// A spot 40 mm above the 10 mm sphere, aimed straight up: its 30° cone misses the sphere.
Light spotAimedAway() {
    Light l;
    l.type = Light::Type::Spot;
    l.position = Point3f(0.f, 40.f, 0.f);
    l.direction = Vector3f(0.f, 1.f, 0.f);
    l.intensity = Rgb(5e4f);
    l.spotOuterDeg = 30.f;
    l.spotInnerDeg = 25.f;
    return l;
}

/// A point light on the side the key light does not reach, at half the skip threshold: its
/// largest irradiance on the bounding sphere is ε/2 of the key light's (3 W/mm², directional).
Light dimPointLight(const Scene& scene) {
    Light l;
    l.position = Point3f(30.f, 10.f, 20.f);
    const Bounds3f b = objectBounds(scene);
    const float near = glm::length(l.position - b.center()) - 0.5f * glm::length(b.extent());
    l.intensity = Rgb(0.5f * LIGHT_SKIP_EPSILON * 3.f * near * near);
    return l;
}

RenderResult render(const Scene& scene, const std::string& method, Backend backend, float eps) {
    RenderOptions o;
    o.backend = backend;
    o.context = backend == Backend::Gl ? test::sharedGlContext() : nullptr;
    o.lightSkipEpsilon = eps;
    ParamSet p;
    if (method == "sslpv")
        p.set("grid", 16);
    if (method == "reference")
        p.set("spp", 4);
    return renderImage(scene, method, p, o);
}

struct Case {
    const char* method;
    Backend backend;
};

class LightSkip : public ::testing::TestWithParam<Case> {};

TEST_P(LightSkip, MissedSpotChangesNothingAndDimLightLessThanEpsilon) {
    const Case c = GetParam();
    if (c.backend == Backend::Gl && !test::sharedGlContext())
        GTEST_SKIP() << "no OpenGL 4.5 context";
    Scene scene = skinSphere();
    scene.lights.push_back(spotAimedAway());
    RenderResult on = render(scene, c.method, c.backend, LIGHT_SKIP_EPSILON);
    RenderResult off = render(scene, c.method, c.backend, -1.f);
    ASSERT_EQ(on.skippedLights.size(), 1u);
    EXPECT_NE(on.skippedLights[0].find("cone misses"), std::string::npos);
    EXPECT_TRUE(off.skippedLights.empty());
    const float peak = test::largestValue(off.radiance);
    ASSERT_GT(peak, 0.f);
    EXPECT_EQ(test::largestDifference(on.radiance, off.radiance), 0.f) << "a missed spot adds zero";

    scene.lights.push_back(dimPointLight(scene));
    on = render(scene, c.method, c.backend, LIGHT_SKIP_EPSILON);
    off = render(scene, c.method, c.backend, -1.f);
    ASSERT_EQ(on.skippedLights.size(), 2u);
    const float moved = test::largestDifference(on.radiance, off.radiance);
    EXPECT_GT(moved, 0.f) << "the dim light is rendered when the skip is off";
    EXPECT_LE(moved, LIGHT_SKIP_EPSILON * peak);
}

INSTANTIATE_TEST_SUITE_P(Methods, LightSkip,
                         ::testing::Values(Case{"direct", Backend::Gl}, Case{"sslpv", Backend::Cpu},
                                           Case{"sslpv", Backend::Gl},
                                           Case{"single-scattering", Backend::Gl}),
                         [](const auto& info) {
                             std::string n = std::string(info.param.method) +
                                             (info.param.backend == Backend::Gl ? "Gl" : "Cpu");
                             n.erase(std::remove(n.begin(), n.end(), '-'), n.end());
                             return n;
                         });

/// Mean green radiance over the pixels `mask` covers (> 0).
double meanOver(const ImageRgb& image, const ImageRgb& mask) {
    double sum = 0.0;
    int n = 0;
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < image.width(); ++x)
            if (mask.at(x, y).g > 0.f) {
                sum += image.at(x, y).g;
                ++n;
            }
    return n ? sum / n : 0.0;
}

// The image-space dipole gathers from a light view per light (docs/methods/dipole.md, light
// views): a skipped spot drops its view, which changes the sample set (its view sees the top of
// the sphere) but not the expectation (the balance heuristic weighs the views). So the test is
// statistical: the mean over the object with the skip on and off, same seed, differs by no more
// than the seed-to-seed spread of that mean allows. With s the sample standard deviation of the
// mean over 4 seeds (3 degrees of freedom), a difference of two such means is within
// t₀.₉₉₅,₃ · √2 · s = 5.84 · √2 · s with 99 % probability.
TEST(LightSkip, DipoleKeepsItsExpectationWhenAMissedSpotIsSkipped) {
    if (!test::sharedGlContext())
        GTEST_SKIP() << "no OpenGL 4.5 context";
    Scene scene = skinSphere();
    scene.lights.push_back(spotAimedAway());
    const auto dipole = [&](float eps, int seed) {
        RenderOptions o;
        o.backend = Backend::Gl;
        o.context = test::sharedGlContext();
        o.lightSkipEpsilon = eps;
        ParamSet p;
        p.set("seed", seed);
        p.set("spp", 64);
        return renderImage(scene, "dipole", p, o);
    };
    const RenderResult on = dipole(LIGHT_SKIP_EPSILON, 1);
    ASSERT_EQ(on.skippedLights.size(), 1u);
    std::vector<double> means;
    ImageRgb mask;
    for (int seed = 1; seed <= 4; ++seed) {
        const RenderResult off = dipole(-1.f, seed);
        if (seed == 1)
            mask = off.radiance;
        means.push_back(meanOver(off.radiance, mask));
    }
    double mean = 0.0, var = 0.0;
    for (double m : means)
        mean += m / double(means.size());
    for (double m : means)
        var += (m - mean) * (m - mean) / double(means.size() - 1);
    const double spread = std::sqrt(var);
    ASSERT_GT(spread, 0.0) << "seeds must change the dipole's samples";
    EXPECT_LE(std::abs(meanOver(on.radiance, mask) - means[0]), 5.84 * std::sqrt(2.0) * spread)
        << "mean with the skip " << meanOver(on.radiance, mask) << ", without " << means[0];
}

TEST(LightSkip, TheReferenceRendersEveryLight) {
    Scene scene = skinSphere();
    scene.camera.width = scene.camera.height = 8;
    scene.lights.push_back(spotAimedAway());
    EXPECT_TRUE(render(scene, "reference", Backend::Cpu, LIGHT_SKIP_EPSILON).skippedLights.empty());
}

}  // namespace
}  // namespace lucent::methods
