// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Meshes generated in code (mm), for the default scene and tests. All closed,
/// 2-manifold, outward counter-clockwise faces, with vertex normals.

#include <lucent/mesh/TriangleMesh.h>

namespace lucent {

/// Icosphere of `radius` mm, `subdivisions` Loop-style splits of an icosahedron.
TriangleMesh makeSphere(float radius, int subdivisions = 4);
/// Axis-aligned box centred at the origin with full edge lengths `size` (mm).
TriangleMesh makeBox(const Vector3f& size);
/// Torus around +y: ring radius `majorRadius`, tube radius `minorRadius` (mm).
TriangleMesh makeTorus(float majorRadius, float minorRadius, int majorSegments = 64,
                       int minorSegments = 32);
/// A shape with thick and thin parts for light bleeding: a thick rounded body with two thin
/// fins ("ears"); `size` is its overall height in mm.
TriangleMesh makeThinThick(float size);

}  // namespace lucent
