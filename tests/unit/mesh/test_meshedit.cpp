// SPDX-License-Identifier: MIT
/// @file
/// @brief Mesh editing through OpenMesh and VTK: decimation, Loop subdivision, smoothing,
/// hole filling, cleaning, largest component.

#include "MeshTestUtil.h"

#include <lucent/core/Error.h>
#include <lucent/mesh/MeshEdit.h>
#include <lucent/mesh/MeshIO.h>
#include <lucent/mesh/Procedural.h>

#include <gtest/gtest.h>

namespace lucent {
namespace {

MeshReport reportOf(TriangleMesh m) {
    return validateMesh(m, "edited");
}

TEST(MeshEdit, DecimateKeepsAClosedSphere) {
    const TriangleMesh src = makeSphere(10.f, 4);  // 5120 faces
    const TriangleMesh lo = decimate(src, 1000);
    EXPECT_LE(lo.triangleCount(), 1000u);
    EXPECT_GE(lo.triangleCount(), 900u);  // collapses remove 2 faces each
    EXPECT_TRUE(reportOf(lo).isClosedManifold());
    // Quadric collapses keep vertices near the surface: volume within 3% of the input's.
    EXPECT_NEAR(test::signedVolume(lo), test::signedVolume(src), 0.03 * test::signedVolume(src));
    EXPECT_THROW(decimate(src, 2), ValueError);
}

TEST(MeshEdit, LoopSubdivisionQuadruplesFaces) {
    const TriangleMesh src = makeSphere(10.f, 1);  // 80 faces
    const TriangleMesh hi = subdivideLoop(src, 2);
    EXPECT_EQ(hi.triangleCount(), 80u * 16u);
    EXPECT_TRUE(test::isClosedOriented(hi));
    // Loop subdivision is approximating: the limit surface lies inside the control mesh's
    // convex hull, so the volume shrinks but stays positive and close.
    EXPECT_LT(test::signedVolume(hi), test::signedVolume(src));
    EXPECT_GT(test::signedVolume(hi), 0.7 * test::signedVolume(src));
    EXPECT_THROW(subdivideLoop(src, 0), ValueError);
}

TEST(MeshEdit, SmoothingShrinksANoisySphere) {
    TriangleMesh noisy = makeSphere(10.f, 3);
    for (size_t i = 0; i < noisy.positions.size(); ++i)  // deterministic ±3% bumps
        noisy.positions[i] *= 1.f + 0.03f * float(int(i % 3) - 1);
    auto roughness = [](const TriangleMesh& m) {
        double s = 0.0, s2 = 0.0;
        for (const auto& p : m.positions) {
            const double r = glm::length(p);
            s += r;
            s2 += r * r;
        }
        const double n = double(m.positions.size());
        return std::sqrt(std::max(0.0, s2 / n - (s / n) * (s / n))) / (s / n);
    };
    const TriangleMesh smooth = smoothLaplacian(noisy, 10);
    EXPECT_EQ(smooth.triangleCount(), noisy.triangleCount());
    EXPECT_LT(roughness(smooth), 0.5 * roughness(noisy));
}

TEST(MeshEdit, FillHolesClosesASmallHole) {
    TriangleMesh holed = makeSphere(10.f, 3);
    std::vector<std::array<uint32_t, 3>> kept;
    for (const auto& t : holed.triangles) {
        const Point3f c =
            (holed.positions[t[0]] + holed.positions[t[1]] + holed.positions[t[2]]) / 3.f;
        if (c.z < 9.7f)
            kept.push_back(t);  // remove a small cap around +z
    }
    ASSERT_LT(kept.size(), holed.triangles.size());
    holed.triangles = kept;
    ASSERT_GT(reportOf(holed).boundaryEdges, 0u);
    const TriangleMesh closed = fillHoles(holed, 5.f);
    const MeshReport r = reportOf(closed);
    EXPECT_EQ(r.boundaryEdges, 0u);
    EXPECT_TRUE(test::isClosedOriented(closed));
    EXPECT_GT(test::signedVolume(closed), 0.95 * 4.0 / 3.0 * M_PI * 1000.0);
    // A hole larger than maxHoleSize stays open.
    EXPECT_GT(reportOf(fillHoles(holed, 0.1f)).boundaryEdges, 0u);
}

TEST(MeshEdit, CleanMergesDuplicatesAndLargestComponentWins) {
    // Two spheres in one mesh, the second smaller; plus split (duplicated) vertices.
    TriangleMesh big = makeSphere(10.f, 2), small = makeSphere(2.f, 2);
    TriangleMesh both = big;
    const auto offset = uint32_t(both.positions.size());
    for (const auto& p : small.positions)
        both.positions.push_back(p + Vector3f(30.f, 0.f, 0.f));
    both.normals.insert(both.normals.end(), small.normals.begin(), small.normals.end());
    for (auto t : small.triangles)
        both.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    const TriangleMesh largest = keepLargestComponent(both);
    EXPECT_EQ(largest.triangleCount(), big.triangleCount());
    EXPECT_EQ(largest.vertexCount(), big.vertexCount());
    EXPECT_LT(largest.bounds().hi.x, 11.f);

    TriangleMesh split;  // every triangle with its own three vertices
    for (const auto& t : big.triangles) {
        const auto base = uint32_t(split.positions.size());
        for (uint32_t v : t)
            split.positions.push_back(big.positions[v]);
        split.triangles.push_back({base, base + 1, base + 2});
    }
    computeVertexNormals(split);
    const TriangleMesh cleaned = cleanMesh(split);
    EXPECT_EQ(cleaned.vertexCount(), big.vertexCount());
    EXPECT_TRUE(reportOf(cleaned).isClosedManifold());
    EXPECT_THROW(cleanMesh(split, -1.f), ValueError);
}

}  // namespace
}  // namespace lucent
