// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief CPU ray picking against a triangle mesh (Möller & Trumbore 1997), for the brush
/// cursor and painting: a brute-force O(triangles) loop behind a bounding-box test, run once
/// per mouse event (the stroke latency in docs/benchmarks.md includes it). In the engine so that
/// the live-cost calibration (lucent/planner/LiveCalibration.h) strokes as the app does.

#include <lucent/mesh/TriangleMesh.h>

#include <optional>

namespace lucent {

struct PickHit {
    float t = 0.f;          ///< ray parameter (mm when the direction is unit)
    Point3f position{0.f};  ///< mm
    Normal3f normal{0.f};   ///< geometric normal facing the ray origin, unit
    uint32_t triangle = 0;
};

/// Nearest intersection of the ray origin + t·direction, t > 0, with the mesh.
std::optional<PickHit> pickMesh(const TriangleMesh& mesh, const Point3f& origin,
                                const Vector3f& direction);

}  // namespace lucent
