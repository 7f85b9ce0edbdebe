// SPDX-License-Identifier: MIT
/// @file
/// @brief Progressive image rendering: determinism, variance layer, stopping rules, cancel.

#include "TestScenes.h"

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>
#include <lucent/reference/PathTracer.h>

#include <gtest/gtest.h>

#include <filesystem>

using namespace lucent;
using namespace lucent::reference;
using namespace lucent::test;

namespace {

Scene smallScene(int width = 24, int height = 16) {
    Scene scene;
    SceneObject obj;
    obj.mesh = boxMesh({-5, -5, -5}, {5, 5, 5});
    MaterialSample s;
    s.sigma_t = Rgb(0.9f, 0.6f, 0.4f);
    s.sigma_s = Rgb(0.8f, 0.5f, 0.2f);
    s.g = Rgb(0.2f);
    const GridSpec spec = GridSpec::around(obj.mesh.bounds(), 16);
    obj.material = std::make_shared<MaterialVolume>(spec, s);
    scene.objects.push_back(std::move(obj));
    Light sun;
    sun.type = Light::Type::Directional;
    sun.direction = glm::normalize(Vector3f(0.4f, -1.f, -0.3f));
    sun.intensity = Rgb(1.f);
    scene.lights.push_back(sun);
    scene.camera.position = {8.f, 6.f, 30.f};
    scene.camera.target = {0.f, 0.f, 0.f};
    scene.camera.fovYDeg = 35.f;
    scene.camera.width = width;
    scene.camera.height = height;
    scene.eta = 1.3f;
    return scene;
}

}  // namespace

TEST(ReferenceRender, SameImageForAnyThreadCount) {
    const Scene scene = smallScene();
    ReferenceOptions o;
    o.spp = 6;
    o.threads = 1;
    const ReferenceImage a = renderReference(scene, o);
    o.threads = 2;
    const ReferenceImage b = renderReference(scene, o);
    ASSERT_EQ(a.spp, 6);
    EXPECT_EQ(a.mean.pixels(), b.mean.pixels());
    EXPECT_EQ(a.variance.pixels(), b.variance.pixels());
    // More threads than cores: tiles land on TBB workers whose floating-point mode must not
    // matter (a denormal once differed between 1 and 16 threads before tiles forced FTZ/DAZ).
    o.threads = 16;
    const ReferenceImage c = renderReference(scene, o);
    EXPECT_EQ(a.mean.pixels(), c.mean.pixels());
    EXPECT_EQ(a.variance.pixels(), c.variance.pixels());
    EXPECT_EQ(a.paths, uint64_t(24 * 16 * 6));
    double covered = 0;
    for (const Rgb& c : a.coverage.pixels())
        covered += c.r;
    EXPECT_GT(covered, 40.0);
}

TEST(ReferenceRender, VarianceLayerPredictsTheErrorBetweenRenders) {
    // Two independent renders differ only by noise: E[(a − b)²] = Var a + Var b per pixel, so
    // the RMSE between them must match the noise floor computed from the variance layers.
    // Over P ≈ 200 covered pixels the RMSE² estimate has relative spread ≈ √(2/P) ≈ 0.1 for
    // Gaussian noise; path-tracing noise has heavier tails, so accept a factor 1.5 each way.
    // Quadrupling N must halve both (1/√N law): accept 2 ± 0.6 on the same grounds.
    const Scene scene = smallScene();
    const auto pair = [&](int spp) {
        ReferenceOptions o;
        o.spp = spp;
        o.seed = 100 + uint64_t(spp);
        const ReferenceImage a = renderReference(scene, o);
        o.seed = 200 + uint64_t(spp);
        const ReferenceImage b = renderReference(scene, o);
        const std::vector<uint8_t> mask = bench::maskFromImage(a.coverage);
        return bench::compareImages(a.mean, b.mean, &b.variance, &a.variance, &mask);
    };
    const bench::ErrorReport n = pair(12), n4 = pair(48);
    const bench::ChannelError& l = n.channels[bench::ErrorReport::LUMINANCE];
    const bench::ChannelError& l4 = n4.channels[bench::ErrorReport::LUMINANCE];
    ASSERT_GT(l.meanReference, 0.0);
    EXPECT_GT(l.rmse / l.rmseFloor, 1 / 1.5);
    EXPECT_LT(l.rmse / l.rmseFloor, 1.5);
    EXPECT_NEAR(l.rmse / l4.rmse, 2.0, 0.6);
    EXPECT_NEAR(l.rmseFloor / l4.rmseFloor, 2.0, 0.6);
}

TEST(ReferenceRender, StopsAtTargetRse) {
    const Scene scene = smallScene();
    ReferenceOptions o;
    o.spp = 3000;
    o.targetRse = 0.08f;
    const ReferenceImage img = renderReference(scene, o);
    EXPECT_LE(img.rse, 0.08f);
    EXPECT_LT(img.spp, 3000);
    EXPECT_GE(img.spp, 12);
}

TEST(ReferenceRender, CancelAndProgress) {
    const Scene scene = smallScene();
    std::atomic<bool> cancel{false};
    int calls = 0;
    ReferenceOptions o;
    o.spp = 300;
    o.cancel = &cancel;
    o.progress = [&](const ReferenceProgress& p) {
        ++calls;
        EXPECT_EQ(p.maxSpp, 300);
        if (p.spp >= 6)
            cancel = true;
    };
    ImageRgb lastPreview;
    o.preview = [&](const ImageRgb& mean) { lastPreview = mean; };
    const ReferenceImage img = renderReference(scene, o);
    EXPECT_TRUE(img.cancelled);
    EXPECT_EQ(lastPreview.pixels(), img.mean.pixels());  // the preview of the last full pass
    EXPECT_EQ(img.spp, 6);
    EXPECT_EQ(calls, 2);
}

TEST(ReferenceRender, RejectsBadInput) {
    Scene scene = smallScene();
    ReferenceOptions o;
    o.spp = 2;
    EXPECT_THROW(renderReference(scene, o), ValueError);
    o.spp = 3;
    o.targetRse = -1.f;
    EXPECT_THROW(renderReference(scene, o), ValueError);
    o.targetRse = 0.f;
    scene.objects.clear();
    EXPECT_THROW(renderReference(scene, o), ValueError);
}

TEST(ReferenceRender, WritesExrWithVarianceAndCoverage) {
    const Scene scene = smallScene(8, 8);
    ReferenceOptions o;
    o.spp = 3;
    const ReferenceImage img = renderReference(scene, o);
    const std::string path = std::string(LUCENT_TEST_OUTPUT_DIR) + "/reference_small.exr";
    writeReferenceExr(img, path);
    const ImageRgb mean = readExr(path), var = readExr(path, "variance"),
                   cov = readExr(path, "coverage");
    EXPECT_EQ(mean.pixels(), img.mean.pixels());
    EXPECT_EQ(var.pixels(), img.variance.pixels());
    EXPECT_EQ(cov.pixels(), img.coverage.pixels());
}

TEST(ReferenceRender, SpectralMisAgreesWithPerChannelTracking) {
    // Two unbiased colour schemes: the error between them must sit at the noise floor their
    // variance layers predict (factor 1.5 either way, as in VarianceLayerPredicts...).
    const Scene scene = smallScene();
    ReferenceOptions o;
    o.spp = 24;
    o.spectralMis = true;
    const ReferenceImage a = renderReference(scene, o);
    o.spectralMis = false;
    o.seed = 9;
    const ReferenceImage b = renderReference(scene, o);
    const std::vector<uint8_t> mask = bench::maskFromImage(a.coverage);
    const bench::ErrorReport r =
        bench::compareImages(a.mean, b.mean, &b.variance, &a.variance, &mask);
    for (int c = 0; c < 4; ++c) {
        EXPECT_GT(r.channels[size_t(c)].rmse / r.channels[size_t(c)].rmseFloor, 1 / 1.5) << c;
        EXPECT_LT(r.channels[size_t(c)].rmse / r.channels[size_t(c)].rmseFloor, 1.5) << c;
    }
}
