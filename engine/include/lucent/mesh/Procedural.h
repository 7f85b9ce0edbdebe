// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Meshes generated in code (mm), for the default scene and tests. All closed,
/// 2-manifold, outward counter-clockwise faces, with vertex normals. Every function throws
/// ValueError for non-finite or non-positive sizes.

#include <lucent/mesh/TriangleMesh.h>

namespace lucent {

/// Icosphere of `radius` mm: an icosahedron split `subdivisions` times (each face into four,
/// new vertices projected onto the sphere), 20·4^subdivisions faces; normals exact.
/// @param subdivisions in [0, 7].
TriangleMesh makeSphere(float radius, int subdivisions = 4);
/// Axis-aligned box centred at the origin with full edge lengths `size` (mm).
TriangleMesh makeBox(const Vector3f& size);
/// Torus around +y: ring radius `majorRadius`, tube radius `minorRadius` (mm), major > minor.
/// @param majorSegments, minorSegments in [3, 4096].
TriangleMesh makeTorus(float majorRadius, float minorRadius, int majorSegments = 64,
                       int minorSegments = 32);
/// A shape with thick and thin parts for light bleeding: a thick rounded body with two thin
/// fins ("ears") along ±x, thin in z (back-light it along z); `size` is its overall height (y
/// extent) in mm; it is about 1.5 × size wide and centred at the origin.
TriangleMesh makeThinThick(float size);

}  // namespace lucent
