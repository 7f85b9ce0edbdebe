// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Edits of a scene that front ends offer (the app's Lights dock and Mesh menu): a light
/// changed to another type with the same irradiance at the object, and the object's mesh
/// edited (decimate, subdivide, smooth, fill holes) and re-voxelised into its material grid.
///
///     lights[i] = convertLight(lights[i], Light::Type::Spot, center, radius);
///     editObjectMesh(scene.objects[0], MeshEditKind::Smooth, {.smoothIterations = 10});

#include <lucent/scene/Scene.h>

namespace lucent {

/// `light` as a light of type `type` that gives the same irradiance (W/mm², at normal
/// incidence) at `target` and keeps its place: a positioned light (point, spot, sphere) keeps
/// its position and aims at `target`; a directional light keeps its direction and becomes a
/// positioned light at distance 1.5·`objectRadius` from `target` (where the
/// app draws its handle). Irradiance at distance d: point/spot E = I/d² (inverse-square
/// law); sphere E = L·πR²/d², from the irradiance integral E = ∫ L cosθ dω (pbrt, 4th ed.,
/// Sec. 4.1) over the cap of half-angle α, sin α = R/d, that the sphere covers:
/// 2πL ∫₀^α cosθ sinθ dθ = πL·sin²α; directional: E is its value. New spot cones open to the
/// object's angular radius asin(objectRadius/d) (+5° outer); a new sphere gets radius
/// min(0.1·objectRadius, 0.5·d). Same type: `light` unchanged.
/// @param target the point the light is aimed at and measured at (mm)
/// @param objectRadius the object's bounding radius (mm), > 0
/// @return the converted light
Light convertLight(const Light& light, Light::Type type, const Point3f& target, float objectRadius);

/// Mesh edits (lucent/mesh/MeshEdit.h) offered on a scene object.
enum class MeshEditKind { Decimate, Subdivide, Smooth, FillHoles };

/// Parameters of the mesh edits (each edit reads its own).
struct MeshEditParams {
    double decimateFraction = 0.5;  ///< decimate: target triangles / current, in (0, 1)
    int subdivideIterations = 1;    ///< Loop subdivision iterations, [1, 5] (×4 each)
    int smoothIterations = 5;       ///< Laplacian smoothing iterations, [1, 1000]
    /// fill holes: largest hole radius closed (mm); ≤ 0: a tenth of the object's diagonal
    double maxHoleMm = -1.0;
};

/// Replaces `object`'s mesh by the edited one and re-voxelises it into the same material grid
/// (the inside mask, MaterialVolume::setInsideMask), so the paint inside is kept: voxels that
/// become inside get the base material. `object` is unchanged when this throws.
/// @param object a scene object with a mesh and a material volume
/// @throw ValueError for an object without a mesh, a parameter out of range (naming it), or an
/// edited mesh that leaves the material grid.
void editObjectMesh(SceneObject& object, MeshEditKind kind, const MeshEditParams& params);

}  // namespace lucent
