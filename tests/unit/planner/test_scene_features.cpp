// SPDX-License-Identifier: MIT
/// @file
/// @brief Scene features on scenes whose values are known in closed form.

#include <lucent/core/Error.h>
#include <lucent/planner/SceneFeatures.h>
#include <lucent/scene/SceneFile.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>

using namespace lucent;
using namespace lucent::planner;
using nlohmann::json;

namespace {

/// A uniform sphere of radius 10 mm (σt′ = 1, σs′ = 0.9 mm⁻¹ in every channel), η 1.3, a
/// camera on +z and one directional light travelling along `travel`.
json sphereScene(const std::array<float, 3>& travel) {
    json j = json::parse(R"({"mesh":{"procedural":"sphere","radius":10},
        "material":{"sigma_t":[1,1,1],"sigma_s":[0.9,0.9,0.9]},"eta":1.3,"resolution":48,
        "camera":{"position":[0,0,60],"target":[0,0,0],"up":[0,1,0],"ortho_height":80,
                  "width":200,"height":200}})");
    j["lights"] = json::array({{{"type", "directional"},
                                {"direction", {travel[0], travel[1], travel[2]}},
                                {"irradiance", {1, 1, 1}}}});
    return j;
}

SceneFeatures featuresOf(const json& j) {
    return analyzeScene(parseScene(j.dump()));
}

}  // namespace

TEST(SceneFeatures, UniformSphereMatchesClosedForms) {
    const SceneFeatures f = featuresOf(sphereScene({0, 0, -1}));  // light from the camera side
    EXPECT_NEAR(f.meanSigmaT, 1.0, 1e-6);
    EXPECT_NEAR(f.meanFreePathMm, 1.0, 1e-6);
    EXPECT_NEAR(f.albedo, 0.9, 1e-6);
    // σtr = √(3·σa·σt′) = √(3·0.1·1) (Jensen et al. 2001, Eq. 5).
    EXPECT_NEAR(f.diffusionLengthMm, 1.0 / std::sqrt(0.3), 1e-5);
    EXPECT_NEAR(f.sigmaTVariation, 0.0, 1e-6);
    EXPECT_NEAR(f.albedoVariation, 0.0, 1e-6);
    EXPECT_DOUBLE_EQ(f.eta, 1.3f);
    // Bounding box of the icosphere inscribed in r = 10: diagonal ≤ 20√3, within 2 %.
    EXPECT_NEAR(f.sizeMm, 20.0 * std::sqrt(3.0), 0.02 * 20.0 * std::sqrt(3.0));
    EXPECT_NEAR(f.opticalSize, f.sizeMm, 1e-6);
    // Deepest voxel ≈ the radius (voxel ≈ 0.43 mm: within two voxels).
    EXPECT_NEAR(f.maxDepthMm, 10.0, 1.0);
    // Inside one diffusion length (1.83 mm) of the surface of a ball of radius 10: the shell
    // 1 − (1 − 1.83/10)³ = 45 % of the volume; voxelisation: within 5 points.
    EXPECT_NEAR(f.thinFraction, 1.0 - std::pow(1.0 - f.diffusionLengthMm / 10.0, 3.0), 0.05);
    EXPECT_NEAR(f.backLitFraction, 0.0, 1e-9);
    EXPECT_NEAR(f.curvature, f.diffusionLengthMm / (0.5 * f.sizeMm), 1e-9);
    // Orthographic, 80 mm over 200 px: bounding-sphere radius ≈ 17.3 mm = 43.3 px.
    const double rPx = 0.5 * f.sizeMm / 80.0 * 200.0;
    EXPECT_NEAR(f.pixelsCovered, 3.14159265358979 * rPx * rPx, 1e-6 * rPx * rPx);
    const SceneClass c = classify(f);
    EXPECT_FALSE(c.backLit);
    EXPECT_TRUE(c.thinParts);  // 45 % of the volume within a diffusion length
    EXPECT_FALSE(c.heterogeneous);
    EXPECT_TRUE(c.dielectric);
    EXPECT_EQ(describe(c, f.eta), "thin parts, front-lit, η 1.3, homogeneous");
}

TEST(SceneFeatures, BackLightIsMeasuredAgainstTheView) {
    // Light travelling toward the camera (+z) comes from behind: 1; from the side: 0; at
    // 45° behind: cos 45°.
    EXPECT_NEAR(featuresOf(sphereScene({0, 0, 1})).backLitFraction, 1.0, 1e-6);
    EXPECT_NEAR(featuresOf(sphereScene({1, 0, 0})).backLitFraction, 0.0, 1e-6);
    const float s = float(std::sqrt(0.5));
    EXPECT_NEAR(featuresOf(sphereScene({s, 0, s})).backLitFraction, std::sqrt(0.5), 1e-6);
    EXPECT_TRUE(classify(featuresOf(sphereScene({0, 0, 1}))).backLit);
}

TEST(SceneFeatures, PaintedVolumeIsHeterogeneous) {
    Scene scene = parseScene(sphereScene({0, 0, -1}).dump());
    MaterialVolume& vol = *scene.objects[0].material;
    const GridSpec& spec = vol.spec();
    // Paint the +x half with σt′ = 3: σt′ is 1 or 3 on (about) half the voxels each, so its
    // coefficient of variation is about 1/2 (mean 2, standard deviation 1).
    for (int z = 0; z < spec.resolution; ++z)
        for (int y = 0; y < spec.resolution; ++y)
            for (int x = spec.resolution / 2; x < spec.resolution; ++x)
                vol.set(Coord(x, y, z), {Rgb(3.f), Rgb(2.7f), Rgb(0.f)});
    const SceneFeatures f = analyzeScene(scene);
    EXPECT_NEAR(f.meanSigmaT, 2.0, 0.1);
    EXPECT_NEAR(f.sigmaTVariation, 0.5, 0.05);
    EXPECT_NEAR(f.albedo, 0.9, 1e-5);  // same albedo on both sides
    EXPECT_TRUE(classify(f).heterogeneous);
}

TEST(SceneFeatures, ThickAbsorbingObjectHasNoThinParts) {
    // σt′ = 10, σs′ = 5: σtr = √(3·5·10) = 12.2 mm⁻¹, a diffusion length of 0.08 mm, under a
    // voxel: only the outermost voxel layer (depth h/2 ≈ 0.2 mm) is not within it.
    json j = sphereScene({0, 0, -1});
    j["material"] = {{"sigma_t", {10, 10, 10}}, {"sigma_s", {5, 5, 5}}};
    const SceneFeatures f = featuresOf(j);
    EXPECT_NEAR(f.diffusionLengthMm, 1.0 / std::sqrt(150.0), 1e-6);
    EXPECT_LT(f.thinFraction, 0.01);
    EXPECT_FALSE(classify(f).thinParts);
}

TEST(SceneFeatures, RejectsAScenelessCall) {
    EXPECT_THROW(analyzeScene(Scene{}), ValueError);
}

TEST(SceneFeatures, StandardScenesAreClassified) {
    // The three scenes of docs/evaluation.md, as the planner sees them.
    struct Expect {
        const char* file;
        bool backLit;
    };
    for (const Expect& e : {Expect{"minimal.json", false}, Expect{"backlit_thin_thick.json", true},
                            Expect{"skin_sphere.json", false}}) {
        const SceneFeatures f =
            analyzeScene(loadScene(std::string(LUCENT_SCENES_DIR) + "/" + e.file));
        const SceneClass c = classify(f);
        std::printf(
            "  %-24s size %.0f mfp, albedo %.3f, l_d %.2f mm, thin %.2f, back-lit %.2f, "
            "curvature %.2f, σt′ variation %.2f: %s\n",
            e.file, f.opticalSize, f.albedo, f.diffusionLengthMm, f.thinFraction, f.backLitFraction,
            f.curvature, f.sigmaTVariation, describe(c, f.eta).c_str());
        EXPECT_EQ(c.backLit, e.backLit) << e.file;
    }
}
