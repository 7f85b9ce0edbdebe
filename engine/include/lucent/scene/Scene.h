// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief What a render needs: a mesh (rest pose), its painted material, lights and a camera.
/// Loaded from / saved to the versioned JSON scene format (docs/file-formats.md) by
/// lucent/scene/SceneFile.h.

#include <lucent/core/Types.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/mesh/TriangleMesh.h>

#include <memory>
#include <string>
#include <vector>

namespace lucent {

/// A light. Units: point/spot intensity in W/sr (per RGB channel); directional irradiance in
/// W/mm² on a surface facing it; sphere light radiance in W/(mm²·sr).
struct Light {
    enum class Type { Point, Spot, Directional, Sphere } type = Type::Point;
    Point3f position{0.f};  ///< point, spot, sphere centre (mm)
    /// Spot axis / directional: the direction the light travels (unit).
    Vector3f direction{0.f, -1.f, 0.f};
    Rgb intensity{0.f};         ///< point/spot: W/sr; directional: W/mm²; sphere: W/(mm²·sr)
    float spotOuterDeg = 30.f;  ///< spot: half-angle where intensity reaches 0
    float spotInnerDeg = 25.f;  ///< spot: half-angle of full intensity
    float radius = 0.f;         ///< sphere light radius (mm)

    /// Intensity (W/sr) toward unit direction `towardSurface` (from the light), including the
    /// spot falloff (smoothstep between outer and inner cones). Point/spot only.
    [[nodiscard]] Rgb intensityToward(const Vector3f& towardSurface) const;
};

/// The type's name as scene files, the CLI and the app spell it: "point", "spot",
/// "directional", "sphere".
[[nodiscard]] const char* lightTypeName(Light::Type type);

/// Pinhole (perspective) or orthographic camera.
struct Camera {
    Point3f position{0.f, 0.f, 60.f};
    Point3f target{0.f};
    Vector3f up{0.f, 1.f, 0.f};
    bool orthographic = false;
    float fovYDeg = 40.f;      ///< perspective: full vertical field of view
    float orthoHeight = 40.f;  ///< orthographic: full view height in mm
    int width = 256;
    int height = 256;
    float nearPlane = 0.1f;  ///< mm
    float farPlane = 1e4f;   ///< mm

    [[nodiscard]] Mat4f viewFromWorld() const;
    [[nodiscard]] Mat4f clipFromView() const;  ///< OpenGL clip convention, depth in [-1, 1]
    /// Primary ray through pixel coordinates (x, y) ∈ [0,w)×[0,h), (0,0) the top-left corner.
    void generateRay(float px, float py, Point3f& origin, Vector3f& direction) const;
};

/// Procedural or file mesh description, kept so the scene can be saved again.
struct MeshSource {
    std::string file;           ///< path when loaded from a file (empty if procedural)
    std::string procedural;     ///< "sphere", "box", "torus", "thin-thick" or empty
    std::vector<float> params;  ///< procedural parameters, see docs/file-formats.md
    float scale = 1.f;          ///< file units → mm
};

/// Material description, kept so the scene can be saved again.
struct MaterialSource {
    std::string vdbFile;   ///< sidecar VDB path, if any
    std::string preset;    ///< preset name, if any
    bool uniform = false;  ///< uniform values given inline
    MaterialSample value;  ///< the uniform value or the preset's value
    int resolution = GridSpec::DEFAULT_RESOLUTION;
};

/// One object with its painted volume.
struct SceneObject {
    MeshSource meshSource;
    TriangleMesh mesh;  ///< rest pose, mm
    MaterialSource materialSource;
    std::shared_ptr<MaterialVolume> material;
};

/// The object `mesh` filled with the uniform material `base`: the material grid placed around
/// the mesh's bounds with `resolution` voxels per axis (GridSpec::around) and the inside mask
/// of the closed mesh (voxelizeSolid), so that voxels outside the mesh are vacuum. Every front
/// end that builds an object from a mesh uses this (scene files, mesh import, `export`,
/// evaluation presets). The material's η is left at its default (callers set the scene's).
/// @param mesh rest pose, mm (moved into the object)
/// @param resolution voxels per axis, in [GridSpec::MIN_RESOLUTION, GridSpec::MAX_RESOLUTION]
/// @param base σ_t, σ_s (mm⁻¹) and g of every inside voxel
/// @return the object; materialSource records `base` (uniform) and `resolution`.
/// @throw ValueError for empty or non-finite mesh bounds or a resolution out of range.
SceneObject makeObject(TriangleMesh mesh, int resolution, const MaterialSample& base);

struct Scene {
    std::vector<SceneObject> objects;  ///< one in the current format
    std::vector<Light> lights;
    /// Radiance of a constant environment light (uniform over all directions, W/(mm²·sr) per
    /// channel), seen wherever a ray leaves the scene; black by default. The path tracer treats
    /// it exactly; the previews may treat it as ambient irradiance (docs/file-formats.md).
    Rgb environment{0.f};
    Camera camera;
    float eta = 1.3f;  ///< relative index of refraction of the object(s)
    /// What loading found and repaired but accepted (e.g. an open mesh, dropped faces): one
    /// line each, for the user to see.
    std::vector<std::string> warnings;
};

}  // namespace lucent
