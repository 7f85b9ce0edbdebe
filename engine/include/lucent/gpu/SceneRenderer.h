// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The first GL passes: mesh upload (re-uploadable every frame), a G-buffer, one shadow
/// map per light, deferred direct lighting (Lambert + normalised Blinn-Phong), an optional
/// per-pixel subsurface radiance term supplied by another pass, and tone mapping to an offscreen
/// target or to a caller's framebuffer (the Qt widget's).
///
/// Usage (headless; the app does the same inside its QOpenGLWidget's current context):
/// @code
///   auto ctx = GlContext::createHeadless();
///   SceneRenderer r;  r.create();                    // compiles programs (context current)
///   r.addMesh(scene.objects[0].mesh);  r.setLights(scene.lights);  r.setCamera(scene.camera);
///   r.render();                                       // camera.width × camera.height
///   ImageRgb hdr = r.readRadiance();                  // linear W/(mm²·sr), top row first
///   r.destroy();
/// @endcode
/// Units: positions mm; point/spot intensity W/sr; directional irradiance W/mm²; radiance
/// W/(mm²·sr). Extension point for subsurface methods: SubsurfaceProvider (docs/gpu.md).

#include <lucent/core/Image.h>
#include <lucent/core/Types.h>
#include <lucent/gpu/GlResources.h>
#include <lucent/gpu/GpuTimer.h>
#include <lucent/gpu/Shader.h>
#include <lucent/mesh/TriangleMesh.h>
#include <lucent/scene/Scene.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace lucent::gpu {

/// Opaque surface reflectance of one mesh for the direct pass.
struct SurfaceMaterial {
    Rgb diffuseAlbedo{0.8f};    ///< Lambert ρ_d ∈ [0,1]
    Rgb specularAlbedo{0.04f};  ///< normalised Blinn-Phong ρ_s ∈ [0,1]
    float shininess = 64.f;     ///< Blinn-Phong exponent m ≥ 1
};

/// Settings of the direct-lighting renderer.
struct DirectSettings {
    bool shadows = true;          ///< one shadow map per light
    int shadowMapSize = 1024;     ///< texels per side of each shadow layer, [16, 8192]
    bool specular = true;         ///< add the Blinn-Phong lobe
    bool subsurfaceOnly = false;  ///< output only the SubsurfaceProvider term (black without one)
    Rgb background{0.f};          ///< radiance of uncovered pixels
    ToneMap toneMap;              ///< for renderToFramebuffer() / readDisplay()
    /// Reuse the G-buffer (camera, meshes and size unchanged) and the direct-lighting term
    /// (G-buffer, shadow maps, lights, surfaces and shading settings unchanged) of the last
    /// frame. A material edit changes none of them, so a paint stroke re-runs only the
    /// subsurface pass, the sum and the tone map; the image is bit-identical to a frame with
    /// false (both passes re-run). Shadow maps are reused while unchanged either way.
    bool reuseUnchangedPasses = true;
};

/// How many times each cacheable pass ran or was reused (since create()).
struct PassReuseCounters {
    long long frames = 0;
    long long shadowsRendered = 0, shadowsReused = 0;  ///< frames with shadows on only
    long long gbufferRendered = 0, gbufferReused = 0;
    long long directRendered = 0, directReused = 0;  ///< the direct-lighting term
};

/// What a plug-in pass may read: the current frame's G-buffer and camera (valid during
/// SubsurfaceProvider::renderSubsurface). Textures are GL names of the renderer's context.
struct GBufferView {
    int width = 0;
    int height = 0;
    unsigned positionTexture = 0;  ///< RGBA32F: world position (mm); a = 1 covered, 0 background
    unsigned normalTexture =
        0;                      ///< RGBA32F: world unit normal (facing the camera); a = mesh id + 1
    unsigned depthTexture = 0;  ///< DEPTH_COMPONENT32F, OpenGL window depth
    Mat4f viewFromWorld{1.f};
    Mat4f clipFromWorld{1.f};
    Point3f cameraPosition{0.f};
    // Lights and shadow maps of the frame (already rendered when the provider runs), for
    // providers that compute their own irradiance (dipole::DipoleSubsurfaceProvider).
    unsigned lightBuffer = 0;        ///< SSBO: GpuLight[lightCount] (shared/LightingShared.h)
    unsigned shadowLayerBuffer = 0;  ///< SSBO: GpuShadowLayer[] referenced by GpuLight::shadow
    unsigned shadowMapTexture = 0;   ///< DEPTH_COMPONENT32F 2-D array, compare mode (PCF)
    int lightCount = 0;
    bool shadows = false;  ///< DirectSettings::shadows: GpuLight::shadow layers are valid
    /// Geometry of the renderer's meshes (index = mesh id), for providers that rasterise the
    /// object from other views (dipole::DirpoleSubsurfaceProvider). The vertex array has
    /// attribute 0 = position (vec3, mm), 1 = normal (vec3), and GL_UNSIGNED_INT triangle indices.
    struct MeshGeometry {
        unsigned vertexArray = 0;
        int indexCount = 0;     ///< 3 × triangles
        Bounds3f bounds;        ///< mm
        uint64_t revision = 0;  ///< changes on every addMesh/updateMesh upload of this mesh
    };
    std::vector<MeshGeometry> meshes;
};

/// A pass adding subsurface (translucency) radiance to every covered pixel. The renderer owns
/// the RGBA32F target texture (width × height, cleared to 0 each frame); the provider writes
/// W/(mm²·sr) into rgb, e.g. with imageStore from a compute shader (bind it with
/// glBindImageTexture) or by attaching it to its own framebuffer. The shading pass adds it.
class SubsurfaceProvider {
public:
    virtual ~SubsurfaceProvider() = default;
    /// Called once per frame after the G-buffer pass, with the renderer's context current.
    virtual void renderSubsurface(const GBufferView& gbuffer, unsigned targetTexture) = 0;
};

/// Column-major OpenGL view matrix of `camera` (right-handed, looking down −z).
Mat4f cameraViewFromWorld(const Camera& camera);
/// OpenGL clip matrix (depth in [−1, 1]) of `camera` at its width/height aspect.
Mat4f cameraClipFromView(const Camera& camera);

/// Deferred direct-lighting renderer. Create/destroy explicitly with a current context.
class SceneRenderer {
public:
    SceneRenderer();
    ~SceneRenderer();
    SceneRenderer(const SceneRenderer&) = delete;
    SceneRenderer& operator=(const SceneRenderer&) = delete;

    /// Compiles the programs from `library` (context current). @throw GpuError on shader errors.
    void create(const ShaderLibrary& library = ShaderLibrary());
    /// Frees every GL object (context current). Idempotent.
    void destroy();
    [[nodiscard]] bool isCreated() const;

    //! @{ \name Scene content
    /// Uploads a mesh; returns its id (0, 1, ...). @throw ValueError for an empty mesh, normals
    /// missing or of the wrong size, or an index out of range.
    int addMesh(const TriangleMesh& mesh, const SurfaceMaterial& material = {});
    /// Re-uploads mesh `id` (deforming meshes: call every frame; the buffers are reused when
    /// the sizes are unchanged). @throw ValueError as addMesh, or for an unknown id.
    void updateMesh(int id, const TriangleMesh& mesh);
    void setSurfaceMaterial(int id, const SurfaceMaterial& material);
    [[nodiscard]] int meshCount() const;
    void clearMeshes();
    /// At most MAX_LIGHTS lights. @throw ValueError for more, or a non-finite light.
    void setLights(const std::vector<Light>& lights);
    /// @throw ValueError for a size outside [1, 16384] or a degenerate camera.
    void setCamera(const Camera& camera);
    void setSettings(const DirectSettings& settings);
    [[nodiscard]] const DirectSettings& settings() const;
    /// Non-owning; nullptr removes it.
    void setSubsurfaceProvider(SubsurfaceProvider* provider);
    //! @}

    //! @{ \name Frames
    /// Runs shadow, G-buffer, subsurface, shading passes into the offscreen HDR target.
    void render();
    /// render(), then tone-maps the result into `framebuffer` (0, or Qt's
    /// defaultFramebufferObject()) over a viewport of width × height pixels.
    void renderToFramebuffer(unsigned framebuffer, int width, int height);
    /// Linear HDR radiance of the last frame, W/(mm²·sr), top row first.
    [[nodiscard]] ImageRgb readRadiance() const;
    /// The last frame after the GPU tone map (display values in [0, 1], sRGB-encoded).
    [[nodiscard]] ImageRgb readDisplay() const;
    /// The last frame's G-buffer (valid until the next render() or a size change).
    [[nodiscard]] GBufferView gbuffer() const;
    /// RGBA32F texture holding the last frame's linear radiance.
    [[nodiscard]] unsigned radianceTexture() const;
    /// Per-pass GPU/CPU timings ("shadows", "gbuffer", "subsurface", "shade", "tonemap").
    GpuProfiler& profiler();
    /// Ran/reused pass counts (DirectSettings::reuseUnchangedPasses).
    [[nodiscard]] const PassReuseCounters& reuseCounters() const;
    /// Forces the next frame to re-run every pass (e.g. after GL state outside the renderer
    /// changed its textures). Context not needed.
    void invalidatePasses();
    //! @}

    static constexpr int MAX_LIGHTS = 8;

private:
    void createPrograms(const ShaderLibrary& library);
    struct Impl;
    std::unique_ptr<Impl> m;
};

}  // namespace lucent::gpu
