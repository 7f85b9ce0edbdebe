// SPDX-License-Identifier: MIT
/// @file
/// @brief Scene edits (lucent/scene/SceneEdit.h): a light's type change keeps the irradiance at
/// the object, and a mesh edit re-voxelises into the same material grid keeping the paint.

#include <lucent/core/Error.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/scene/SceneEdit.h>

#include "LightIrradiance.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace lucent {

TEST(LightTypes, ConversionKeepsTheIrradianceAtTheTarget) {
    const Point3f target(1.f, 2.f, 3.f);
    const float objectRadius = 10.f;
    Light point;
    point.type = Light::Type::Point;
    point.position = target + Vector3f(0.f, 30.f, 40.f);  // d = 50 mm
    point.intensity = Rgb(2500.f, 1250.f, 500.f);         // E = 1, 0.5, 0.2 W/mm²
    const Rgb e0 = test::irradianceAt(point, target);
    ASSERT_LT(test::relDiff(e0, Rgb(1.f, 0.5f, 0.2f)), 1e-5f);
    const Light::Type types[] = {Light::Type::Point, Light::Type::Spot, Light::Type::Directional,
                                 Light::Type::Sphere};
    for (Light::Type a : types)
        for (Light::Type b : types) {
            const Light la = convertLight(point, a, target, objectRadius);
            const Light lb = convertLight(la, b, target, objectRadius);
            EXPECT_EQ(lb.type, b);
            // float32 arithmetic on values of order 1e3: a few ulps.
            EXPECT_LT(test::relDiff(test::irradianceAt(la, target), e0), 1e-5f) << int(a);
            EXPECT_LT(test::relDiff(test::irradianceAt(lb, target), e0), 1e-5f)
                << int(a) << "→" << int(b);
            if (b == Light::Type::Spot || b == Light::Type::Directional) {
                // Aimed at the target: the light travels along the axis from it to the target.
                const Point3f from = a == Light::Type::Directional
                                         ? target - 1.5f * objectRadius * la.direction
                                         : la.position;
                EXPECT_LT(glm::length(lb.direction - glm::normalize(target - from)), 1e-5f);
            }
        }
    // Positioned lights keep their place; a directional one becomes a light at its handle.
    EXPECT_EQ(convertLight(point, Light::Type::Sphere, target, objectRadius).position,
              point.position);
    const Light sun = convertLight(point, Light::Type::Directional, target, objectRadius);
    const Light back = convertLight(sun, Light::Type::Point, target, objectRadius);
    EXPECT_LT(glm::length(back.position - (target - 15.f * sun.direction)), 1e-4f);
    // A new spot cone holds the whole bounding sphere: asin(10/50) = 11.54°.
    const Light spot = convertLight(point, Light::Type::Spot, target, objectRadius);
    EXPECT_NEAR(spot.spotInnerDeg, glm::degrees(std::asin(0.2f)), 1e-3f);
    EXPECT_NEAR(spot.spotOuterDeg, spot.spotInnerDeg + 5.f, 1e-4f);
    const Light sphere = convertLight(point, Light::Type::Sphere, target, objectRadius);
    EXPECT_GT(sphere.radius, 0.f);
    EXPECT_LT(sphere.radius, 25.f);  // outside the target by at least half the distance
}

TEST(MeshEdits, ReVoxeliseIntoTheSameGridAndKeepThePaint) {
    SceneObject object = makeObject(makeSphere(/*radius=*/10.f), /*resolution=*/32,
                                    MaterialSample{Rgb(1.f), Rgb(0.9f), Rgb(0.f)});
    const GridSpec spec = object.material->spec();
    // Paint one voxel at the centre (inside before and after a smoothing).
    const Coord centre(spec.resolution / 2);
    const MaterialSample painted{Rgb(4.f), Rgb(1.f), Rgb(0.f)};
    object.material->set(centre, painted);
    const size_t before = object.mesh.triangleCount();
    MeshEditParams params;
    params.subdivideIterations = 1;
    editObjectMesh(object, MeshEditKind::Subdivide, params);
    EXPECT_EQ(object.mesh.triangleCount(), 4 * before);  // Loop subdivision: ×4 per iteration
    EXPECT_EQ(object.material->spec().resolution, spec.resolution);
    EXPECT_EQ(object.material->spec().origin, spec.origin);
    EXPECT_EQ(object.material->at(centre).sigma_t, painted.sigma_t);
    // A bad parameter is named and changes nothing.
    const size_t after = object.mesh.triangleCount();
    params.decimateFraction = 1.5;
    try {
        editObjectMesh(object, MeshEditKind::Decimate, params);
        ADD_FAILURE() << "decimate fraction 1.5 accepted";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("decimate"), std::string::npos) << e.what();
    }
    EXPECT_EQ(object.mesh.triangleCount(), after);
    // An object without a mesh has nothing to edit.
    SceneObject empty;
    EXPECT_THROW(editObjectMesh(empty, MeshEditKind::Smooth, params), ValueError);
}

}  // namespace lucent
