// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Time-varying deformers (twist, bend, ripple) and a sculpt-style displacement brush.
///
/// Deformers map the REST mesh to a deformed pose for display; nothing is precomputed and the
/// rest mesh is never modified, so `deform(rest, stack, t)` can be called every frame. The
/// material volume stays in rest space: a renderer that needs the material at a deformed
/// point uses the rest-space position of the same surface point (docs/conventions.md).
///
///     Deformer twist;
///     twist.type = DeformerType::Twist;
///     twist.amount = 0.05f;          // rad per mm along the axis
///     twist.rateHz = 0.5f;           // animated: amount · sin(2π · 0.5 · t)
///     TriangleMesh posed = deform(rest, {twist}, /*timeSeconds=*/1.2f);
///
/// The displacement brush, in contrast, edits the rest shape itself (sculpting): after it the
/// caller re-voxelises the mesh to update the material's inside mask.

#include <lucent/mesh/TriangleMesh.h>

#include <vector>

namespace lucent {

enum class DeformerType { Twist, Bend, Ripple };

/// One deformer; all lengths in mm, angles in radians, time in seconds.
struct Deformer {
    DeformerType type = DeformerType::Twist;
    Point3f center{0.f};                 ///< a point on the deformer's axis (mm)
    Vector3f axis{0.f, 1.f, 0.f};        ///< twist/bend/ripple axis (normalised internally)
    Vector3f bendToward{1.f, 0.f, 0.f};  ///< Bend: direction the axis curves toward (⊥ axis)
    /// Twist: rotation per mm along the axis (rad/mm). Bend: curvature of the bent axis
    /// (1/mm; 0 = straight). Ripple: amplitude of the displacement along the axis (mm).
    float amount = 0.f;
    float wavelength = 10.f;  ///< Ripple: radial wavelength (mm), > 0
    /// Twist/Bend: when > 0 the amount oscillates as amount·sin(2π·rateHz·t).
    /// Ripple: waves travel outward, phase 2π(ρ/wavelength − rateHz·t).
    float rateHz = 0.f;
};

/// Applies `stack` in order to the rest mesh at time `timeSeconds`; normals are recomputed
/// from the deformed triangles. @throw ValueError naming the field for invalid parameters.
TriangleMesh deform(const TriangleMesh& rest, const std::vector<Deformer>& stack,
                    float timeSeconds);

/// Deformed position of one rest-space point (the same map deform() applies to vertices).
Point3f deformPoint(const Point3f& rest, const std::vector<Deformer>& stack, float timeSeconds);

/// Sculpt brush: moves every vertex within `radius` mm of `center` along its normal by
/// amount·(1 − smoothstep(0, 1, d/radius)) mm (negative amount pushes in), then recomputes
/// normals. @return number of vertices moved. @throw ValueError for radius ≤ 0 or NaN input.
size_t displaceBrush(TriangleMesh& mesh, const Point3f& center, float radius, float amount);

}  // namespace lucent
