// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief CPU irradiance pass for the image-space dipole (seed 004 §5): ray-casts the scene's
/// camera against the object (Embree via lucent/reference/MeshBoundary.h), computes the
/// Fresnel-transmitted irradiance E (Eq. 5) of every light with a shadow ray, and reads the
/// painted material just inside the surface. Then renderImageSpaceDipole() gathers.
///
///     SurfaceBuffers buf = buildSurfaceBuffers(scene);
///     GatherResult g = gatherImageSpace(buf, settings);   // or renderImageSpaceDipole(scene,
///     settings)

#include <lucent/dipole/ImageSpace.h>
#include <lucent/scene/Scene.h>

namespace lucent::dipole {

/// Irradiance E at a surface point from one light (Eq. 5 for delta lights):
/// F_t(η, cos θ_i) · I(ω)·cos θ_i/d² (point, spot; W/sr → W/mm²) or F_t · I·cos θ_i (directional,
/// W/mm²). Sphere lights are treated as points of intensity L·πR² (W/sr) — an approximation
/// valid for distances ≫ R. Shadowing is not included here.
Rgb lightIrradiance(const Light& light, const Point3f& p, const Normal3f& n, float eta);

/// Camera-view buffers of `scene.objects[objectIndex]` (pixel centres, scene.camera size).
/// Pixels that miss the object stay uncovered. Irradiance includes shadow rays against the
/// object itself (the scene holds one object). The material is sampled half a voxel inside,
/// stepping further in (≤ 3 voxels) past masked-out voxels cut by the surface.
/// @throw ValueError if the scene has no such object, no material, or a bad camera.
SurfaceBuffers buildSurfaceBuffers(const Scene& scene, int objectIndex = 0);

/// buildSurfaceBuffers + gatherImageSpace with settings.eta = scene.eta. The returned radiance is
/// the subsurface term only (the specular reflection of delta lights is a highlight of zero
/// width and is left out).
GatherResult renderImageSpaceDipole(const Scene& scene, GatherSettings settings);

}  // namespace lucent::dipole
