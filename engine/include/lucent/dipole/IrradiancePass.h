// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief CPU irradiance pass for the image-space dipole (Mertens et al. 2005 §5): ray-casts the
/// scene's camera against the object (Embree via lucent/reference/MeshBoundary.h), computes the
/// Fresnel-transmitted irradiance E (Eq. 5) of every light with a shadow ray, and reads the
/// painted material just inside the surface. Light views (Mertens et al. 2005 §7.1) are the same
/// pass from each light. Then renderImageSpaceDipole() gathers.
///
///     SurfaceBuffers buf = buildSurfaceBuffers(scene);
///     GatherResult g = gatherImageSpace(buf, settings);   // or renderImageSpaceDipole(scene,
///     settings)

#include <lucent/dipole/ImageSpace.h>
#include <lucent/scene/Scene.h>

#include <string>
#include <vector>

namespace lucent::dipole {

/// Irradiance E at a surface point from one light (Eq. 5 for delta lights):
/// F_t(η, cos θ_i) · I(ω)·cos θ_i/d² (point, spot; W/sr → W/mm²) or F_t · I·cos θ_i (directional,
/// W/mm²). Sphere lights are treated as points of intensity L·πR² (W/sr) — an approximation
/// valid for distances ≫ R. Shadowing is not included here.
Rgb lightIrradiance(const Light& light, const Point3f& p, const Normal3f& n, float eta);

/// The painted material just inside the surface point `p` (mm) with outward unit normal `n`:
/// the first non-empty voxel among p − k·(h/2)·n, k = 1..6 (voxels cut by the surface may be
/// masked out), else the nearest non-empty voxel (by cell centre) in the first shell of
/// Chebyshev radius 1..4 voxels around the voxel of p − (h/2)·n that holds one (a hole in the
/// inside mask under the surface, as where two closed parts of a mesh overlap). Zero when
/// neither finds material. The GPU providers use the same rule (shaders/dipole_material.glsl).
MaterialSample materialInside(const MaterialVolume& volume, const Point3f& p, const Normal3f& n);

/// Camera-view buffers of `scene.objects[objectIndex]` (pixel centres, scene.camera size).
/// Pixels that miss the object stay uncovered. Irradiance includes shadow rays against the
/// object itself (the scene holds one object). The material is materialInside().
/// @throw ValueError if the scene has no such object, no material, or a bad camera.
SurfaceBuffers buildSurfaceBuffers(const Scene& scene, int objectIndex = 0);

/// Irradiance image rendered from light `lightIndex` (Mertens et al. 2005 §7.1), same content as
/// the camera's (positions, normals, E of *all* lights with shadow rays, material), so that the
/// gather can combine both: orthographic along the light for a directional light (square,
/// framing the object's bounding sphere), perspective from the light's position towards the
/// bounding sphere's centre for point, spot and sphere lights (a field of view that just frames
/// the sphere). @param resolution texels per side, [16, 4096].
/// @throw ValueError for a bad index or resolution, or a point/spot/sphere light inside the
/// object's bounding sphere (no perspective view frames the object from there).
SurfaceBuffers buildLightViewBuffers(const Scene& scene, int lightIndex, int resolution,
                                     int objectIndex = 0);

/// The light-view camera of buildLightViewBuffers() for an object with bounds `objectBounds`
/// (also used by the GL provider). @throw ValueError for a point/spot/sphere light inside the
/// bounding sphere.
Camera lightViewCamera(const Light& light, const Bounds3f& objectBounds, int resolution);

/// When renderImageSpaceDipole() renders and gathers the light views.
struct LightViewSettings {
    bool enabled = true;   ///< false: camera image only (the seed-004 method as published)
    int resolution = 512;  ///< texels per side of each light view, [16, 4096]
    /// A light view is gathered only if backlitFluxFraction() > threshold, i.e. enough of the
    /// light's flux lands on surfaces the camera cannot see within the gather radius behind
    /// camera-visible points; otherwise it is skipped (its rendering is cheap; gathering it
    /// would take a share of the per-pixel samples and add visibility tests for nothing).
    /// [0, 1).
    double threshold = 1e-3;
    /// true: gather every built view whatever its back-lit fraction (the skip above off). A view
    /// at back-lit fraction 0 adds no surface the camera misses, so the expectation is the same
    /// either way (balance heuristic over images); the reference of the skip's equivalence test
    /// and of its measured saving (docs/benchmarks.md, "Skips").
    bool gatherAll = false;
};

/// What happened to one light's view.
struct LightViewReport {
    int light = 0;
    bool built = false;  ///< rendered (false: disabled, or a light inside the bounding sphere)
    bool used = false;   ///< gathered (backlitFraction > threshold, or gatherAll)
    double backlitFraction = 0.0;  ///< backlitFluxFraction() of the view
    std::string note;              ///< why it was not built, if not
};

/// The camera image and the light views worth gathering (see LightViewSettings).
struct ImageSpaceViews {
    SurfaceBuffers camera;
    std::vector<SurfaceBuffers> lights;    ///< only the used ones
    std::vector<LightViewReport> reports;  ///< one per scene light
};

/// buildSurfaceBuffers + buildLightViewBuffers per light + the skip criterion.
/// @throw ValueError as buildSurfaceBuffers, or for bad LightViewSettings.
ImageSpaceViews buildImageSpaceViews(const Scene& scene, const GatherSettings& settings,
                                     const LightViewSettings& lightViews, int objectIndex = 0);

/// buildImageSpaceViews + gatherImageSpace with settings.eta = scene.eta. The returned radiance
/// is the subsurface term only (the specular reflection of delta lights is a highlight of zero
/// width and is left out). `reports`, if given, receives the light views' reports.
GatherResult renderImageSpaceDipole(const Scene& scene, GatherSettings settings,
                                    const LightViewSettings& lightViews = {},
                                    std::vector<LightViewReport>* reports = nullptr);

}  // namespace lucent::dipole
