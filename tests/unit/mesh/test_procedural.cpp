// SPDX-License-Identifier: MIT
/// @file
/// @brief Procedural meshes: closed, outward, correct size and volume; deformers.

#include "MeshTestUtil.h"

#include <lucent/core/Error.h>
#include <lucent/mesh/Deform.h>
#include <lucent/mesh/MeshIO.h>
#include <lucent/mesh/Procedural.h>

#include <gtest/gtest.h>

#include <cmath>

namespace lucent {
namespace {

void expectWellFormed(const TriangleMesh& m) {
    ASSERT_FALSE(m.isEmpty());
    ASSERT_EQ(m.normals.size(), m.positions.size());
    EXPECT_TRUE(test::isClosedOriented(m));
    TriangleMesh copy = m;
    const MeshReport r = validateMesh(copy, "procedural");
    EXPECT_TRUE(r.isClosedManifold());
    EXPECT_EQ(r.degenerateDropped, 0u);
    EXPECT_FALSE(r.normalsComputed);
    EXPECT_GT(test::signedVolume(m), 0.0);  // outward orientation
    // Vertex normals point away from the centroid of their one-ring on average: check that
    // the area-weighted normal agrees in sign with each face normal for most faces.
    size_t agree = 0;
    for (const auto& t : m.triangles) {
        const Vector3f fn = glm::cross(m.positions[t[1]] - m.positions[t[0]],
                                       m.positions[t[2]] - m.positions[t[0]]);
        if (glm::dot(fn, m.normals[t[0]] + m.normals[t[1]] + m.normals[t[2]]) > 0.f)
            ++agree;
    }
    EXPECT_EQ(agree, m.triangles.size());
}

TEST(Procedural, SphereIsClosedWithExactVolumeBound) {
    const float r = 10.f;
    const TriangleMesh m = makeSphere(r, 4);
    expectWellFormed(m);
    EXPECT_EQ(m.triangleCount(), 20u * 256u);
    for (const auto& p : m.positions)
        EXPECT_NEAR(glm::length(p), r, 1e-4f * r);
    // An inscribed polyhedron: its volume is below the sphere's. Its deficit is about
    // 3 × (mean depth of a face below the sphere) / r ≈ 0.2% for 5120 faces (edge angle
    // ≈ 4°); 1% leaves margin.
    const double analytic = 4.0 / 3.0 * M_PI * r * r * r;
    EXPECT_LT(test::signedVolume(m), analytic);
    EXPECT_GT(test::signedVolume(m), 0.99 * analytic);
}

TEST(Procedural, BoxTorusThinThickAreClosedAndOutward) {
    const TriangleMesh box = makeBox({10.f, 20.f, 30.f});
    expectWellFormed(box);
    EXPECT_NEAR(test::signedVolume(box), 6000.0, 1e-2);  // exact for a box
    const Bounds3f bb = box.bounds();
    EXPECT_FLOAT_EQ(bb.hi.z - bb.lo.z, 30.f);

    const float R = 10.f, rr = 3.f;
    const TriangleMesh torus = makeTorus(R, rr, 96, 48);
    expectWellFormed(torus);
    // Polygonal torus: inscribed polygons in both directions; the volume deficit is about
    // (1 − sin(2π/n)/(2π/n)) per direction, < 0.2% each for n = 48 and 96.
    const double analytic = 2.0 * M_PI * M_PI * R * rr * rr;
    EXPECT_NEAR(test::signedVolume(torus), analytic, 0.006 * analytic);

    const float size = 40.f;
    const TriangleMesh tt = makeThinThick(size);
    expectWellFormed(tt);
    const Bounds3f tb = tt.bounds();
    EXPECT_NEAR(tb.hi.y - tb.lo.y, size, 1e-3f * size);
    // Thin parts: the shape's z thickness near its x extremes is far below the body's.
    float thickAtEar = 0.f, thickAtBody = 0.f;
    for (const auto& p : tt.positions) {
        if (std::abs(p.x) > 0.8f * tb.hi.x)
            thickAtEar = std::max(thickAtEar, std::abs(p.z));
        if (std::abs(p.x) < 0.05f * tb.hi.x)
            thickAtBody = std::max(thickAtBody, std::abs(p.z));
    }
    EXPECT_LT(thickAtEar, 0.2f * thickAtBody);
}

TEST(Procedural, InvalidParametersThrow) {
    EXPECT_THROW(makeSphere(-1.f), ValueError);
    EXPECT_THROW(makeSphere(NAN), ValueError);
    EXPECT_THROW(makeBox({1.f, 0.f, 1.f}), ValueError);
    EXPECT_THROW(makeTorus(1.f, 2.f), ValueError);
    EXPECT_THROW(makeThinThick(0.f), ValueError);
}

TEST(Deform, TwistRotatesAboutTheAxisAndPreservesRadius) {
    const TriangleMesh rest = makeBox({10.f, 40.f, 10.f});
    Deformer tw;
    tw.type = DeformerType::Twist;
    tw.amount = 0.02f;  // rad/mm: 0.8 rad over the 40 mm height
    const TriangleMesh posed = deform(rest, {tw}, 0.f);
    ASSERT_EQ(posed.positions.size(), rest.positions.size());
    for (size_t i = 0; i < rest.positions.size(); ++i) {
        const Point3f a = rest.positions[i], b = posed.positions[i];
        EXPECT_NEAR(a.y, b.y, 1e-5f);
        EXPECT_NEAR(glm::length(glm::vec2(a.x, a.z)), glm::length(glm::vec2(b.x, b.z)), 1e-4f);
        // Right-handed rotation about +y turns x toward −z: atan2(z, x) falls by amount × height.
        const float turned = std::atan2(b.z, b.x) - std::atan2(a.z, a.x);
        if (glm::length(glm::vec2(a.x, a.z)) > 1e-3f) {
            EXPECT_NEAR(std::remainder(turned + 0.02f * a.y, 2.f * PI), 0.f, 1e-3f)
                << "vertex " << i;
        }
    }
    // Twisting is volume preserving; the tessellation (0.1 rad per 5 mm row of quads) only
    // bends the side faces' chords: a relative error of order 0.1²/2 = 0.5%, test at 2%.
    EXPECT_NEAR(test::signedVolume(posed), test::signedVolume(rest),
                0.02 * test::signedVolume(rest));
    // Rest mesh untouched and an oscillating twist is the identity at t = 0.
    tw.rateHz = 1.f;
    const TriangleMesh still = deform(rest, {tw}, 0.f);
    for (size_t i = 0; i < rest.positions.size(); ++i)
        EXPECT_NEAR(glm::length(still.positions[i] - rest.positions[i]), 0.f, 1e-5f);
}

TEST(Deform, BendMapsTheAxisOntoACircleAndRippleIsAxial) {
    Deformer bend;
    bend.type = DeformerType::Bend;
    bend.amount = 1.f / 20.f;  // curvature 1/mm: radius 20 mm
    for (float h : {-10.f, 5.f, 15.f}) {
        const Point3f p = deformPoint({0.f, h, 0.f}, {bend}, 0.f);
        // On the circle of radius 20 centred at (20, 0, 0), arc length h from the origin.
        EXPECT_NEAR(glm::length(p - Point3f(20.f, 0.f, 0.f)), 20.f, 1e-4f);
        EXPECT_NEAR(std::asin(p.y / 20.f), h / 20.f, 1e-4f);
    }
    Deformer rip;
    rip.type = DeformerType::Ripple;
    rip.amount = 2.f;
    rip.wavelength = 8.f;
    rip.rateHz = 0.25f;
    const Point3f q = deformPoint({2.f, 1.f, 0.f}, {rip}, 1.f);
    EXPECT_FLOAT_EQ(q.x, 2.f);
    EXPECT_FLOAT_EQ(q.z, 0.f);
    EXPECT_NEAR(q.y, 1.f + 2.f * std::sin(2.f * PI * (2.f / 8.f - 0.25f)), 1e-5f);
    rip.wavelength = 0.f;
    EXPECT_THROW(deformPoint({0.f, 0.f, 0.f}, {rip}, 0.f), ValueError);
}

TEST(Deform, DisplacementBrushMovesAlongNormalsWithinRadius) {
    TriangleMesh m = makeSphere(10.f, 4);
    const Point3f centre(0.f, 0.f, 10.f);
    const TriangleMesh before = m;
    const size_t moved = displaceBrush(m, centre, 3.f, 1.f);
    EXPECT_GT(moved, 0u);
    for (size_t i = 0; i < m.positions.size(); ++i) {
        const float d = glm::length(before.positions[i] - centre);
        const Vector3f delta = m.positions[i] - before.positions[i];
        if (d >= 3.f) {
            EXPECT_EQ(delta, Vector3f(0.f));
        } else {
            // Along the (radial) normal by 1 − smoothstep(d / r).
            const float t = d / 3.f;
            EXPECT_NEAR(glm::dot(delta, before.normals[i]), 1.f - t * t * (3.f - 2.f * t), 1e-4f);
            EXPECT_NEAR(glm::length(glm::cross(delta, before.normals[i])), 0.f, 1e-4f);
        }
    }
    EXPECT_THROW(displaceBrush(m, centre, 0.f, 1.f), ValueError);
}

}  // namespace
}  // namespace lucent
