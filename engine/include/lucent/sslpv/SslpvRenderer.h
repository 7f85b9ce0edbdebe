// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief CPU SSLPV renderer: reflective shadow maps per light (§3.1), the SslpvSolver, and a
/// ray-cast image with the subsurface term of §3.3 plus direct Blinn–Phong reflection with
/// ray-traced shadows. Incremental, for the app's live preview:
///
///     SslpvRenderer r(options);
///     r.setMesh(mesh);                    // BVH + re-injection
///     r.setLights(scene.lights);          // re-injection only
///     r.setMaterial(volume, scene.eta);   // resample to the LPV grid, re-propagation only
///     ImageRgb img = r.render(scene.camera);
///
/// Units: mm, W/sr (point/spot), W/mm² (directional), radiance W/(mm²·sr).

#include <lucent/core/Image.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/mesh/TriangleMesh.h>
#include <lucent/scene/Scene.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <memory>
#include <vector>

namespace lucent {
class RayCaster;
}

namespace lucent::sslpv {

/// Renderer settings. Injection texels come from one reflective shadow map per light (§3.1):
/// point and spot lights outside the mesh's bounding sphere use one perspective map aimed at
/// it (FOV just covering the sphere), lights inside it a six-face cube map; directional lights
/// an orthographic map over the bounding sphere (Φ_p = E·A_texel); sphere lights are treated as
/// point lights of intensity L·πr². Shadows of the direct term are ray traced (exact), so there
/// is no separate shadow-map resolution on the CPU.
struct SslpvRenderOptions {
    SslpvOptions solver;            ///< propagation settings
    int gridResolution = 32;        ///< LPV cells per axis, [4, 256] (≤ the material's)
    int injectionResolution = 256;  ///< RSM texels per side used for injection, [8, 4096]
    bool subsurface = true;         ///< add the SSLPV term (Eq. 7)
    bool direct = true;             ///< add direct Blinn–Phong reflection with shadows
    float specularWeight = 1.f;     ///< scales the Fresnel-weighted specular lobe, ≥ 0
    float shininess = 64.f;         ///< Blinn–Phong exponent, [1, 10000]
    Rgb diffuseReflectance{0.f};    ///< extra Lambertian reflection, [0, 1] (0: SSS only)
};

/// Per-pass CPU timings of the last update()/render(), milliseconds.
struct SslpvRenderTimings {
    double rsmMs = 0.0;
    double resampleMs = 0.0;
    double injectMs = 0.0;
    double propagateMs = 0.0;
    double shadeMs = 0.0;
};

class SslpvRenderer {
public:
    /// @throw ValueError for options out of range.
    explicit SslpvRenderer(const SslpvRenderOptions& options = {});
    ~SslpvRenderer();
    SslpvRenderer(const SslpvRenderer&) = delete;
    SslpvRenderer& operator=(const SslpvRenderer&) = delete;

    /// @throw ValueError for options out of range.
    void setOptions(const SslpvRenderOptions& options);
    [[nodiscard]] const SslpvRenderOptions& options() const { return m_opt; }
    /// New or deformed mesh: rebuilds the BVH, re-voxelises the LPV grid, re-injects.
    /// @throw ValueError for an empty/invalid mesh.
    void setMesh(const TriangleMesh& mesh);
    /// Lights changed: re-injection (and propagation) only.
    void setLights(const std::vector<Light>& lights);
    /// Material painted or replaced: resamples to gridResolution³ (resampleForPropagation)
    /// and re-propagates. @param eta relative index of refraction, [1, 3].
    void setMaterial(const MaterialVolume& volume, float eta);

    /// Runs what is dirty (RSM → injection → propagation). @throw ValueError if the mesh or
    /// material is missing.
    const SslpvStats& update();
    /// update() then ray casts the image. @throw ValueError for a camera with no pixels.
    ImageRgb render(const Camera& camera);

    [[nodiscard]] const SslpvSolver& solver() const { return m_solver; }
    [[nodiscard]] const SslpvRenderTimings& timings() const { return m_timings; }

private:
    void applyInsideMask();

    SslpvRenderOptions m_opt;
    SslpvSolver m_solver;
    std::unique_ptr<RayCaster> m_rays;
    TriangleMesh m_mesh;
    std::vector<Light> m_lights;
    CoarseMaterial m_coarse;
    float m_eta = 1.3f;
    bool m_hasMaterial = false;
    bool m_rsmDirty = true;
    bool m_materialDirty = true;
    SslpvRenderTimings m_timings;
};

/// Fraction of each cell of `spec` inside `mesh` (closed), from a solid voxelisation at
/// `subdivisions`³ sub-cells per cell: the partial cells along the surface that the solver's
/// partial sinks use (SslpvSolver: a cell keeps min(1, 2f) of its light).
/// @throw ValueError for subdivisions outside [1, 8].
std::vector<float> meshInsideFractions(const TriangleMesh& mesh, const GridSpec& spec,
                                       int subdivisions = 4);

/// One-shot render of scene.objects[0] with the scene's lights and camera.
/// @throw ValueError if the scene has no object, mesh or material.
ImageRgb renderSslpv(const Scene& scene, const SslpvRenderOptions& options = {},
                     SslpvRenderTimings* timings = nullptr, SslpvStats* stats = nullptr);

}  // namespace lucent::sslpv
