// SPDX-License-Identifier: MIT
/// @file
/// @brief Solid voxelisation: volumes within the discretisation bound, robustness on open
/// meshes, grids that cover only part of a mesh, boundary cells.

#include "MeshTestUtil.h"

#include <lucent/core/Error.h>
#include <lucent/mesh/MeshIO.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/mesh/Voxelize.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numeric>

namespace lucent {
namespace {

/// Cubic grid of `n` cells covering `b` plus a 1.5-voxel pad (what GridSpec::around does;
/// built here so the mesh tests do not need the material library).
GridSpec gridAround(const Bounds3f& b, int n) {
    const Vector3f e = b.extent();
    const float side = std::max({e.x, e.y, e.z});
    GridSpec s;
    s.resolution = n;
    s.voxelSize = side / (float(n) - 3.f);
    s.origin = b.center() - Vector3f(0.5f * s.voxelSize * float(n));
    return s;
}

size_t countSet(const std::vector<uint8_t>& v) {
    return size_t(std::count_if(v.begin(), v.end(), [](uint8_t x) { return x != 0; }));
}

/// Cells whose classification can differ from the exact solid: those with a face neighbour of
/// the other state (inside boundary cells plus outside cells touching the inside).
size_t transitionCells(const std::vector<uint8_t>& inside, const GridSpec& spec) {
    std::vector<uint8_t> outside(inside.size());
    for (size_t i = 0; i < inside.size(); ++i)
        outside[i] = inside[i] ? 0 : 1;
    return countSet(boundaryCells(inside, spec)) + countSet(boundaryCells(outside, spec)) -
           // boundaryCells treats the grid's exterior as "outside": outside cells on the grid
           // faces are not transitions, remove them (none touch the solid thanks to the pad).
           [&] {
               const size_t n = size_t(spec.resolution);
               return n * n * n - (n - 2) * (n - 2) * (n - 2);
           }();
}

/// Voxelised volume vs the exact polyhedron volume. Each cell contributes h³ by its centre;
/// the true solid volume inside a cell is between 0 and h³, so only cells the surface cuts can
/// be wrong, by at most h³ each. At this resolution (≥ 6 cells per radius) every cut cell has
/// a face neighbour of the other state, so |V_vox − V| ≤ transitionCells × h³. (In practice
/// the errors cancel and the error is about 100× smaller.)
void expectVolumeWithinBound(const TriangleMesh& mesh, int n, double analytic) {
    const GridSpec spec = gridAround(mesh.bounds(), n);
    const auto inside = voxelizeSolid(mesh, spec);
    const double h3 = double(spec.voxelSize) * spec.voxelSize * spec.voxelSize;
    const double vox = double(countSet(inside)) * h3;
    const double bound = double(transitionCells(inside, spec)) * h3;
    const double poly = test::signedVolume(mesh);
    EXPECT_NEAR(vox, poly, bound) << "n = " << n;
    EXPECT_NEAR(vox, analytic, bound + std::abs(poly - analytic)) << "n = " << n;
    // The bound must be meaningful: well below the volume itself.
    EXPECT_LT(bound, 0.5 * poly);
}

TEST(Voxelize, SphereVolumeWithinDiscretisationBound) {
    const float r = 10.f;
    const TriangleMesh m = makeSphere(r, 5);
    for (int n : {24, 64, 128})
        expectVolumeWithinBound(m, n, 4.0 / 3.0 * M_PI * r * r * r);
}

TEST(Voxelize, TorusVolumeWithinDiscretisationBound) {
    const float R = 10.f, rr = 4.f;
    const TriangleMesh m = makeTorus(R, rr, 128, 64);
    for (int n : {96, 128})
        expectVolumeWithinBound(m, n, 2.0 * M_PI * M_PI * R * rr * rr);
}

TEST(Voxelize, CellCentresClassifiedExactlyAwayFromTheSurface) {
    // Every centre farther than the polyhedron's chord error (+ a float margin) from the
    // sphere must be classified exactly, including on a grid covering only part of the mesh.
    const float r = 10.f;
    const TriangleMesh m = makeSphere(r, 5);
    GridSpec spec;
    spec.resolution = 40;
    spec.voxelSize = 0.4f;
    spec.origin = Point3f(-2.f, -9.f, 1.f);  // a window through the sphere's surface
    const auto inside = voxelizeSolid(m, spec);
    const float chord = 0.02f * r;  // > max depth of a face below the sphere for 20480 faces
    size_t checked = 0;
    for (int z = 0; z < spec.resolution; ++z)
        for (int y = 0; y < spec.resolution; ++y)
            for (int x = 0; x < spec.resolution; ++x) {
                const Coord c(x, y, z);
                const float d = glm::length(spec.cellCenter(c));
                if (std::abs(d - r) < chord)
                    continue;
                ++checked;
                ASSERT_EQ(inside[spec.linearIndex(c)] != 0, d < r) << x << "," << y << "," << z;
            }
    EXPECT_GT(checked, 60000u);
}

TEST(Voxelize, GridAlignedBoxWithEdgesOnRayLines) {
    // Box faces, edges and vertices lie exactly on the lines of cell centres the rays follow
    // (rays graze faces and pass through edges/vertices): every cell whose centre is not on
    // the surface must still be classified exactly.
    const TriangleMesh box = makeBox({10.f, 6.f, 8.f});
    GridSpec spec;
    spec.resolution = 32;
    spec.voxelSize = 0.5f;
    spec.origin = Point3f(-8.25f);  // centres at −8 + 0.5·i: on x = ±5, y = ±3, z = ±4
    const auto inside = voxelizeSolid(box, spec);
    size_t checked = 0;
    for (int z = 0; z < spec.resolution; ++z)
        for (int y = 0; y < spec.resolution; ++y)
            for (int x = 0; x < spec.resolution; ++x) {
                const Coord c(x, y, z);
                const Point3f p = spec.cellCenter(c);
                const Vector3f d = glm::abs(p) - Vector3f(5.f, 3.f, 4.f);
                const float m = std::max({d.x, d.y, d.z});
                if (std::abs(m) < 1e-3f)
                    continue;  // centre on the surface: either is right
                ++checked;
                ASSERT_EQ(inside[spec.linearIndex(c)] != 0, m < 0.f) << x << "," << y << "," << z;
            }
    EXPECT_GT(checked, 30000u);
}

TEST(Voxelize, RobustOnMeshWithHoles) {
    // A sphere with triangles removed in three places (one on each axis' column direction):
    // single-direction parity would flip whole columns; majority voting must not.
    const float r = 10.f;
    const TriangleMesh closed = makeSphere(r, 4);
    TriangleMesh holed = closed;
    std::vector<std::array<uint32_t, 3>> kept;
    size_t removed = 0;
    for (const auto& t : holed.triangles) {
        const Point3f c =
            (holed.positions[t[0]] + holed.positions[t[1]] + holed.positions[t[2]]) / 3.f;
        const Vector3f u = glm::normalize(c);
        // Caps of ~8° around +z, +x and −y.
        if (u.z > 0.99f || u.x > 0.99f || u.y < -0.99f) {
            ++removed;
            continue;
        }
        kept.push_back(t);
    }
    holed.triangles = kept;
    ASSERT_GT(removed, 10u);
    TriangleMesh check = holed;
    const MeshReport report = validateMesh(check, "holed");
    EXPECT_GT(report.boundaryEdges, 0u);  // really open

    // A grid reaching well beyond the sphere (side 1.6 × diameter): a column whose parity is
    // broken by a hole would mislabel every cell past the hole, ≈ 10 cells per column here.
    GridSpec spec;
    spec.resolution = 64;
    spec.voxelSize = 1.6f * 2.f * r / 64.f;
    spec.origin = Point3f(-0.8f * 2.f * r) + Vector3f(0.013f, -0.021f, 0.017f) * spec.voxelSize;
    const auto ref = voxelizeSolid(closed, spec);
    const auto got = voxelizeSolid(holed, spec);
    size_t differ = 0;
    for (size_t i = 0; i < ref.size(); ++i)
        differ += ref[i] != got[i];
    // Lines through a hole have an odd crossing count and are discarded; the two other axes
    // decide. Only cells whose other lines also graze a hole's rim can change: a handful.
    // (Single-axis parity mislabels ≈ 10 cells for each of the ≈ 30 columns through each hole.)
    EXPECT_LE(differ, 10u) << differ << " cells differ";
}

TEST(Voxelize, BoundaryCellsOfAFullGridAreItsShell) {
    GridSpec spec;
    spec.resolution = 10;
    std::vector<uint8_t> all(spec.voxelCount(), 1);
    EXPECT_EQ(countSet(boundaryCells(all, spec)), 1000u - 512u);
    std::vector<uint8_t> one(spec.voxelCount(), 0);
    one[spec.linearIndex({4, 5, 6})] = 1;
    EXPECT_EQ(countSet(boundaryCells(one, spec)), 1u);
    EXPECT_THROW(boundaryCells(std::vector<uint8_t>(5), spec), ValueError);
}

TEST(Voxelize, EmptyAndInvalidInput) {
    GridSpec spec;
    spec.resolution = 16;
    EXPECT_EQ(countSet(voxelizeSolid(TriangleMesh{}, spec)), 0u);
    TriangleMesh bad = makeSphere(1.f, 1);
    bad.positions[3].x = NAN;
    EXPECT_THROW(voxelizeSolid(bad, spec), ValueError);
    spec.voxelSize = 0.f;
    EXPECT_THROW(voxelizeSolid(makeSphere(1.f, 1), spec), ValueError);
}

TEST(Voxelize, ClosedBunnyIfPresent) {
    const std::string path = std::string(LUCENT_SHARED_DIR) + "/meshes/bunny_closed_75k.ply";
    if (!std::filesystem::exists(path))
        GTEST_SKIP() << path << " not present";
    MeshReport report;
    const TriangleMesh bunny = loadMesh(path, /*scale=*/100.f, &report);
    EXPECT_TRUE(report.isClosedManifold());
    const double poly = test::signedVolume(bunny);
    ASSERT_GT(poly, 0.0);
    const GridSpec spec = gridAround(bunny.bounds(), 64);
    const auto inside = voxelizeSolid(bunny, spec);
    const double h3 = double(spec.voxelSize) * spec.voxelSize * spec.voxelSize;
    EXPECT_NEAR(double(countSet(inside)) * h3, poly, double(transitionCells(inside, spec)) * h3);
}

}  // namespace
}  // namespace lucent
