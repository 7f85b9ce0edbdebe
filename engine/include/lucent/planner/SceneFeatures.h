// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief What a scene is, in the terms that decide which translucency method it needs: how
/// thick the object is in mean free paths and diffusion lengths, its albedo, how heterogeneous
/// its painted volume is, η and g, whether its light comes from behind, how far its curvature
/// departs from a half-space, and how many pixels it covers. The Auto planner
/// (lucent/planner/Planner.h) predicts each method's cost and error from these.
///
///     const SceneFeatures f = analyzeScene(scene);
///     const SceneClass c = classify(f);     // re-plan when this changes
///     std::cout << describe(c);              // "thick, front-lit, η 1.3, homogeneous"
///
/// Units: mm, mm⁻¹. Channel values are combined with the Rec. 709 luminance weights.

#include <lucent/scene/Scene.h>

#include <string>

namespace lucent::planner {

struct SceneFeatures {
    double sizeMm = 0.0;          ///< diagonal of the object's bounding box
    double meanSigmaT = 0.0;      ///< mean reduced extinction σt′ over inside voxels, mm⁻¹
    double meanFreePathMm = 0.0;  ///< 1 / meanSigmaT
    double opticalSize = 0.0;     ///< sizeMm / meanFreePathMm (object size in mean free paths)
    double albedo = 0.0;          ///< mean reduced albedo α′ = σs′/σt′ over inside voxels
    double diffusionLengthMm = 0.0;  ///< 1/σtr, σtr = √(3σa σt′) of the mean medium (Jensen 2001
                                     ///< Eq. 5); capped at sizeMm when σa → 0
    double sigmaTVariation = 0.0;  ///< coefficient of variation of σt′ over inside voxels
    double albedoVariation = 0.0;  ///< standard deviation of α′ over inside voxels
    double meanAbsG = 0.0;         ///< mean |g|
    double eta = 1.0;              ///< relative index of refraction
    double maxDepthMm = 0.0;       ///< deepest inside voxel below the surface (half thickness)
    /// Fraction of inside voxels within one diffusion length of the surface: where light that
    /// enters on one side still reaches the other (thin parts).
    double thinFraction = 0.0;
    /// Fraction of the light reaching the object (irradiance at its centre) that arrives from
    /// the side facing away from the camera, weighted by −cos between light and view: 0 for
    /// front light, 1 for light straight from behind.
    double backLitFraction = 0.0;
    /// Diffusion length over the radius of the object's bounding sphere: 0 is a half-space, ≥ 1
    /// an object about as small as the light's spread inside it.
    double curvature = 0.0;
    double pixelsCovered = 0.0;  ///< projected bounding sphere, pixels (clipped to the image)
    double imagePixels = 0.0;    ///< camera width × height
    int insideVoxels = 0;
    int lights = 0;
};

/// Measures object 0 of `scene` (its mesh, painted volume, lights and camera).
/// @throw ValueError if the scene has no object with a material or the volume has no inside
///        voxel.
SceneFeatures analyzeScene(const Scene& scene);

/// The coarse class of a scene: the planner keeps its choice while the class stays the same
/// (no flicker while the artist paints) and re-plans when it changes.
struct SceneClass {
    bool backLit = false;        ///< backLitFraction > 0.5
    bool thinParts = false;      ///< thinFraction > 0.25
    bool heterogeneous = false;  ///< sigmaTVariation > 0.1 or albedoVariation > 0.05
    bool dielectric = false;     ///< η > 1.01
    bool operator==(const SceneClass&) const = default;
};

SceneClass classify(const SceneFeatures& features);

/// "thin parts, back-lit, η 1.3, heterogeneous" (η printed from the features when given).
std::string describe(const SceneClass& sceneClass, double eta = 0.0);

}  // namespace lucent::planner
