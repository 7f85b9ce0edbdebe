// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Mesh editing with library code: OpenMesh quadric decimation, Loop subdivision and
/// Laplacian smoothing; VTK hole filling, cleaning and largest-component extraction. Every
/// function returns a new mesh with fresh vertex normals, leaves its input untouched and
/// throws ValueError for an empty mesh or a parameter outside its documented range.
///
///     TriangleMesh lo = decimate(mesh, /*targetTriangles=*/5000);
///     TriangleMesh closed = fillHoles(scan, /*maxHoleSize=*/20.f);   // mm

#include <lucent/mesh/TriangleMesh.h>

#include <cstddef>

namespace lucent {

/// Quadric-error-metric edge-collapse decimation (Garland & Heckbert 1997) via OpenMesh's
/// DecimaterT + ModQuadricT, down to about `targetTriangles` faces.
/// @throw ValueError if the mesh is empty or targetTriangles < 4.
TriangleMesh decimate(const TriangleMesh& mesh, size_t targetTriangles);

/// Loop subdivision (Loop 1987) via OpenMesh's Subdivider::Uniform::LoopT; each iteration
/// multiplies the triangle count by 4. @param iterations in [1, 5].
TriangleMesh subdivideLoop(const TriangleMesh& mesh, int iterations);

/// Uniform Laplacian smoothing (OpenMesh JacobiLaplaceSmootherT, tangential and normal
/// movement, C0 continuity). @param iterations in [1, 1000].
TriangleMesh smoothLaplacian(const TriangleMesh& mesh, int iterations);

/// Closes boundary loops whose bounding-sphere radius is below `maxHoleSize` mm
/// (vtkFillHolesFilter), then makes face orientation consistent (vtkPolyDataNormals).
TriangleMesh fillHoles(const TriangleMesh& mesh, float maxHoleSize);

/// Merges points closer than `tolerance` mm and removes degenerate cells and unused points
/// (vtkCleanPolyData). @param tolerance ≥ 0 (0: exact duplicates only).
TriangleMesh cleanMesh(const TriangleMesh& mesh, float tolerance = 0.f);

/// Keeps only the connected component with the most cells (vtkPolyDataConnectivityFilter).
TriangleMesh keepLargestComponent(const TriangleMesh& mesh);

}  // namespace lucent
