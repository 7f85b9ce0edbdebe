// SPDX-License-Identifier: MIT
/// @file
/// @brief Camera: generated rays agree with the viewFromWorld/clipFromView projection;
/// light falloff.

#include <lucent/scene/Scene.h>

#include <gtest/gtest.h>

#include <cmath>

namespace lucent {
namespace {

/// Projects a world point to pixel coordinates with the camera's matrices.
glm::vec2 projectToPixel(const Camera& cam, const Point3f& p) {
    const glm::vec4 clip = cam.clipFromView() * cam.viewFromWorld() * glm::vec4(p, 1.f);
    const glm::vec3 ndc = glm::vec3(clip) / clip.w;
    return {(ndc.x + 1.f) * 0.5f * float(cam.width), (1.f - ndc.y) * 0.5f * float(cam.height)};
}

void expectRaysMatchProjection(const Camera& cam) {
    for (float py : {0.5f, 37.25f, 100.f, float(cam.height) - 0.5f})
        for (float px : {0.5f, 13.f, 160.5f, float(cam.width) - 0.5f}) {
            Point3f o;
            Vector3f d;
            cam.generateRay(px, py, o, d);
            EXPECT_NEAR(glm::length(d), 1.f, 1e-5f);
            for (float t : {5.f, 40.f, 300.f}) {
                const glm::vec2 pix = projectToPixel(cam, o + t * d);
                // float32 matrices: ~1e-6 relative error of coordinates ≈ 1e-3 px at 320 px.
                EXPECT_NEAR(pix.x, px, 2e-3f * float(cam.width) / 320.f) << px << "," << py;
                EXPECT_NEAR(pix.y, py, 2e-3f * float(cam.height) / 320.f) << px << "," << py;
            }
        }
}

Camera testCamera() {
    Camera cam;
    cam.position = {10.f, 20.f, 60.f};
    cam.target = {1.f, -2.f, 3.f};
    cam.up = {0.f, 1.f, 0.f};
    cam.width = 320;
    cam.height = 200;
    cam.fovYDeg = 35.f;
    return cam;
}

TEST(Camera, PerspectiveRaysMatchProjection) {
    expectRaysMatchProjection(testCamera());
}

TEST(Camera, OrthographicRaysMatchProjection) {
    Camera cam = testCamera();
    cam.orthographic = true;
    cam.orthoHeight = 30.f;
    expectRaysMatchProjection(cam);
    // Parallel rays, one orthoHeight apart from the top to the bottom edge.
    Point3f o0, o1;
    Vector3f d0, d1;
    cam.generateRay(160.f, 0.f, o0, d0);
    cam.generateRay(160.f, 200.f, o1, d1);
    EXPECT_NEAR(glm::length(d0 - d1), 0.f, 1e-6f);
    EXPECT_NEAR(glm::length(o0 - o1), 30.f, 1e-4f);
}

TEST(Camera, ViewSpaceConventions) {
    const Camera cam = testCamera();
    const Mat4f v = cam.viewFromWorld();
    const glm::vec4 eye = v * glm::vec4(cam.position, 1.f);
    EXPECT_NEAR(glm::length(glm::vec3(eye)), 0.f, 1e-4f);
    const glm::vec4 tgt = v * glm::vec4(cam.target, 1.f);
    EXPECT_NEAR(tgt.x, 0.f, 1e-4f);
    EXPECT_NEAR(tgt.y, 0.f, 1e-4f);
    EXPECT_NEAR(tgt.z, -glm::length(cam.target - cam.position), 1e-3f);  // looks down −z
    // The centre of the image looks at the target; depth maps into [−1, 1] (OpenGL).
    Point3f o;
    Vector3f d;
    cam.generateRay(160.f, 100.f, o, d);
    EXPECT_GT(glm::dot(d, glm::normalize(cam.target - cam.position)), 1.f - 1e-6f);
    const glm::vec4 clipNear = cam.clipFromView() * glm::vec4(0.f, 0.f, -cam.nearPlane, 1.f);
    EXPECT_NEAR(clipNear.z / clipNear.w, -1.f, 1e-4f);
    // Pixel (0, 0) is the top-left corner: its ray points up and left of the axis.
    cam.generateRay(0.f, 0.f, o, d);
    const glm::vec3 dv = glm::mat3(v) * d;
    EXPECT_LT(dv.x, 0.f);
    EXPECT_GT(dv.y, 0.f);
}

TEST(Light, PointAndSpotIntensity) {
    Light p;
    p.intensity = Rgb(1.f, 2.f, 3.f);
    EXPECT_EQ(p.intensityToward({0.f, 0.f, 1.f}), Rgb(1.f, 2.f, 3.f));
    Light s;
    s.type = Light::Type::Spot;
    s.direction = {0.f, -1.f, 0.f};
    s.intensity = Rgb(10.f);
    s.spotInnerDeg = 20.f;
    s.spotOuterDeg = 30.f;
    auto at = [](float deg) {
        const float r = glm::radians(deg);
        return Vector3f(std::sin(r), -std::cos(r), 0.f);
    };
    EXPECT_EQ(s.intensityToward(at(0.f)), Rgb(10.f));
    EXPECT_EQ(s.intensityToward(at(19.f)), Rgb(10.f));
    EXPECT_EQ(s.intensityToward(at(31.f)), Rgb(0.f));
    const float c = std::cos(glm::radians(25.f)), co = std::cos(glm::radians(30.f)),
                ci = std::cos(glm::radians(20.f));
    const float t = (c - co) / (ci - co);
    EXPECT_NEAR(s.intensityToward(at(25.f)).r, 10.f * t * t * (3.f - 2.f * t), 1e-4f);
    Light dir;
    dir.type = Light::Type::Directional;
    EXPECT_EQ(dir.intensityToward({0.f, 1.f, 0.f}), Rgb(0.f));
}

}  // namespace
}  // namespace lucent
