// SPDX-License-Identifier: MIT
/// @file
/// @brief RayCaster: hits on a procedural icosphere against the analytic sphere, the (tNear, tFar]
/// segment, occlusion, rays starting inside, thread safety, and input validation.

#include <lucent/core/Error.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/mesh/RayCaster.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>
#include <vector>

namespace lucent {
namespace {

constexpr float R = 10.f;  // sphere radius, mm

/// Smallest distance from the centre to a face plane of the icosphere (its inradius h): the
/// polyhedron lies between the spheres of radius h and R (vertices on the sphere, flat faces
/// inside it), which brackets every hit distance analytically.
float inradius(const TriangleMesh& m) {
    float h = R;
    for (const auto& t : m.triangles) {
        const Vector3f n = glm::normalize(glm::cross(m.positions[t[1]] - m.positions[t[0]],
                                                     m.positions[t[2]] - m.positions[t[0]]));
        h = std::min(h, glm::dot(n, m.positions[t[0]]));
    }
    return h;
}

// Float rounding of Embree's ray–triangle test and of our normal arithmetic: a few ulps of
// coordinates of magnitude ~3R (ulp(30) ≈ 1.9e-6 mm); 1e-4 mm leaves ample room.
constexpr float EPS_T = 1e-4f;
// Unit vectors computed in float: a few ulps of 1 (6e-8); 1e-5 leaves ample room.
constexpr float EPS_N = 1e-5f;

TEST(RayCaster, RaysFromCentreHitAtRadiusWithOutwardNormals) {
    const TriangleMesh m = makeSphere(R, 3);
    const RayCaster caster(m);
    const float h = inradius(m);
    ASSERT_GT(h, 0.99f * R);  // sanity: 3 subdivisions, sagitta ≈ R·θ²/2 well below 1 %
    EXPECT_EQ(caster.triangleCount(), m.triangleCount());
    EXPECT_NEAR(caster.bounds().hi.x, R, EPS_T);
    const Vector3f dirs[] = {{1, 0, 0}, {0, 1, 0},  {0, 0, -1},
                             {1, 2, 3}, {-3, 1, 2}, {0.3f, -0.9f, 0.1f}};
    for (Vector3f d : dirs) {
        d = glm::normalize(d);
        const auto hit = caster.intersect(Point3f(0.f), d, 0.f, INF);
        ASSERT_TRUE(hit.has_value());
        // A ray from the centre crosses the face at distance in [h, R].
        EXPECT_GE(hit->t, h - EPS_T);
        EXPECT_LE(hit->t, R + EPS_T);
        EXPECT_NEAR(glm::length(hit->position - hit->t * d), 0.f, EPS_T);
        // Geometric normal: unit, the normal of the reported triangle, outward; its angle to
        // d is at most the face's angular radius, so cos ≥ h/R (point on the face, |x| ≤ R).
        EXPECT_NEAR(glm::length(hit->geometricNormal), 1.f, EPS_N);
        ASSERT_LT(hit->triangle, m.triangleCount());
        EXPECT_EQ(hit->geometricNormal, caster.faceNormal(hit->triangle));
        EXPECT_GE(glm::dot(hit->geometricNormal, d), h / R - EPS_N);
        // The hit lies in the plane of its triangle.
        const Point3f& p0 = m.positions[m.triangles[hit->triangle][0]];
        EXPECT_NEAR(glm::dot(hit->position - p0, hit->geometricNormal), 0.f, EPS_T);
        // Shading normal: the exact vertex normals v_i/R interpolated with the barycentrics of
        // p = Σ b_i v_i give p/R, so normalised it is p/|p| = d (ray from the centre).
        EXPECT_NEAR(glm::length(hit->shadingNormal - d), 0.f, EPS_N);
    }
}

TEST(RayCaster, RaysFromOutsideHitWithinAnalyticBracket) {
    const TriangleMesh m = makeSphere(R, 3);
    const RayCaster caster(m);
    const float h = inradius(m);
    const Point3f base(0.f, 0.f, -3.f * R);
    const Vector3f d(0.f, 0.f, 1.f);
    for (float a : {0.f, 0.3f * R, 0.6f * R, 0.9f * R}) {
        const Point3f o = base + Vector3f(a, 0.f, 0.f);
        const auto hit = caster.intersect(o, d, 0.f, INF);
        ASSERT_TRUE(hit.has_value()) << "impact parameter " << a;
        // Entry through the polyhedron lies between the sphere of radius R (outside it) and
        // the insphere of radius h: 3R − √(R² − a²) ≤ t ≤ 3R − √(h² − a²).
        EXPECT_GE(hit->t, 3.f * R - std::sqrt(R * R - a * a) - EPS_T);
        EXPECT_LE(hit->t, 3.f * R - std::sqrt(h * h - a * a) + EPS_T);
        EXPECT_LT(glm::dot(hit->geometricNormal, d), 0.f);  // entering: normal faces the ray
        // (tNear, tFar]: the hit distance itself is inside the segment...
        const auto same = caster.intersect(o, d, 0.f, hit->t);
        ASSERT_TRUE(same.has_value());
        EXPECT_EQ(same->t, hit->t);
        EXPECT_TRUE(caster.occluded(o, d, 0.f, hit->t));
        // ...a segment ending just before it sees nothing...
        EXPECT_FALSE(caster.intersect(o, d, 0.f, 0.999f * hit->t).has_value());
        EXPECT_FALSE(caster.occluded(o, d, 0.f, 0.999f * hit->t));
        // ...and one starting just after it finds the exit on the far side, outward normal.
        const auto exit = caster.intersect(o, d, hit->t * 1.0001f, INF);
        ASSERT_TRUE(exit.has_value());
        EXPECT_GE(exit->t, 3.f * R + std::sqrt(h * h - a * a) - EPS_T);
        EXPECT_LE(exit->t, 3.f * R + std::sqrt(R * R - a * a) + EPS_T);
        EXPECT_GT(glm::dot(exit->geometricNormal, d), 0.f);
    }
    // Beyond the radius the ray misses.
    const Point3f miss = base + Vector3f(1.01f * R, 0.f, 0.f);
    EXPECT_FALSE(caster.intersect(miss, d, 0.f, INF).has_value());
    EXPECT_FALSE(caster.occluded(miss, d, 0.f, INF));
}

TEST(RayCaster, RayStartingInsideLeavesOnce) {
    const TriangleMesh m = makeSphere(R, 3);
    const RayCaster caster(m);
    const float h = inradius(m);
    const Point3f o(0.2f * R, -0.1f * R, 0.3f * R);
    const Vector3f d = glm::normalize(Vector3f(-1.f, 2.f, 0.5f));
    const auto hit = caster.intersect(o, d, 0.f, INF);
    ASSERT_TRUE(hit.has_value());
    EXPECT_GT(glm::dot(hit->geometricNormal, d), 0.f);  // leaving through an outward face
    const float r = glm::length(hit->position);
    EXPECT_GE(r, h - EPS_T);
    EXPECT_LE(r, R + EPS_T);
    // Nothing between the start and just before the exit; nothing after the exit.
    EXPECT_FALSE(caster.occluded(o, d, 0.f, 0.999f * hit->t));
    EXPECT_TRUE(caster.occluded(o, d, 0.f, 2.f * R));
    EXPECT_FALSE(caster.intersect(o, d, hit->t * 1.0001f, INF).has_value());
}

TEST(RayCaster, ConcurrentQueriesMatchSerial) {
    const TriangleMesh m = makeSphere(R, 3);
    const RayCaster caster(m);
    constexpr int N = 512;
    std::vector<Vector3f> dirs(N);
    for (int i = 0; i < N; ++i) {  // Fibonacci-sphere directions
        const float z = 1.f - 2.f * (float(i) + 0.5f) / float(N);
        const float phi = 2.39996323f * float(i);
        const float s = std::sqrt(1.f - z * z);
        dirs[size_t(i)] = Vector3f(s * std::cos(phi), s * std::sin(phi), z);
    }
    std::vector<float> serial(N), parallel(N);
    for (int i = 0; i < N; ++i)
        serial[size_t(i)] = caster.intersect(Point3f(0.f), dirs[size_t(i)], 0.f, INF)->t;
    std::vector<std::thread> threads;
    for (int k = 0; k < 4; ++k)
        threads.emplace_back([&, k] {
            for (int i = k; i < N; i += 4) {
                const auto hit = caster.intersect(Point3f(0.f), dirs[size_t(i)], 0.f, INF);
                parallel[size_t(i)] = hit ? hit->t : -1.f;
            }
        });
    for (auto& t : threads)
        t.join();
    EXPECT_EQ(serial, parallel);
}

TEST(RayCaster, RejectsBadMeshes) {
    EXPECT_THROW(RayCaster(TriangleMesh{}), ValueError);
    TriangleMesh bad = makeSphere(R, 1);
    bad.triangles[3][1] = uint32_t(bad.positions.size());
    EXPECT_THROW(RayCaster{bad}, ValueError);
    TriangleMesh nan = makeSphere(R, 1);
    nan.positions[5].y = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(RayCaster{nan}, ValueError);
    TriangleMesh inf = makeSphere(R, 1);
    inf.positions[0].z = INF;
    EXPECT_THROW(RayCaster{inf}, ValueError);
}

}  // namespace
}  // namespace lucent
