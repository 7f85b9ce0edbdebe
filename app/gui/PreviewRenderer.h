// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The viewport's rendering, outside the widget: gpu::SceneRenderer (direct lighting,
/// shadow maps, tone map) with one subsurface provider per preview method (single scattering,
/// SSLPV, dipole / better dipole, directional dipole, combined), the volume overlay and the
/// brush-cursor overlay. Every shader comes from the engine's shader library
/// (shaders/preview_*.{comp,frag}). Plain C++ and GL (epoxy): the Qt widget only hands it a
/// current context, its framebuffer and the frame's inputs.
///
/// Paint strokes: the renderer keeps the shadow maps, the G-buffer and the direct-lighting term
/// while lights, camera and mesh are unchanged, so a stroke frame runs only the subsurface
/// provider, a one-fetch shading pass and the tone map (RenderSettings::reusePasses).
///
/// Material edits: the caller passes the volume's dirty bricks (MaterialVolume::takeDirtyBricks)
/// once per frame; the active method consumes them incrementally (SSLPV re-resamples and
/// re-propagates only the coarse cells they overlap, the dipole and single-scatter passes
/// re-upload only those bricks). Inactive methods are fully re-synchronised when selected.

#include <lucent/core/Image.h>
#include <lucent/core/Types.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/mesh/TriangleMesh.h>
#include <lucent/scene/Scene.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace lucent::gpu {
class ShaderLibrary;
}

namespace lucent::app {

/// Preview method and its parameters.
struct RenderSettings {
    enum class Method {
        Direct = 0,            ///< SceneRenderer direct lighting of an opaque grey surface
        SingleScattering = 1,  ///< + ray-marched single scattering (preview_single_scatter.comp)
        Sslpv = 2,             ///< + SSLPV (Børlum et al. 2011), SslpvSubsurfaceProvider
        Dipole = 3,            ///< + image-space dipole (Jensen et al. 2001), progressive
        BetterDipole = 4,      ///< + image-space better dipole (d'Eon 2012), progressive
        /// + directional dipole (Frisvad et al. 2014), GPU pipeline, progressive
        /// (dipole::DirpoleSubsurfaceProvider; needs a build with that provider)
        DirectionalDipole = 5,
        /// + windowed dipole and SSLPV beyond the split radius (combined::
        /// CombinedSubsurfaceProvider; only in builds with the combined module)
        Combined = 6,
    } method = Method::Dipole;  ///< shows paint at once (SSLPV Paper 32³ hid a dark stroke)
    int steps = 24;             ///< view-ray march steps (single scattering)
    int lightSteps = 6;         ///< shadow-ray march steps per view step (single scattering)
    float exposureStops = 2.f;  ///< log2 of the exposure multiplier (Reinhard tone curve)
    float ambient = 0.f;        ///< uniform ambient irradiance, W/mm² (single scattering only)
    bool turntable = false;     ///< rotate the camera at 30°/s
    /// Trilinear texture filtering of σ in the single-scattering pass (display only; the
    /// engine's lookup rule is nearest).
    bool smoothVoxels = false;
    /// Preview pixels per widget pixel per axis (1, ½, ¼); the image is upscaled bilinearly by
    /// the tone-map pass.
    float resolutionScale = 0.5f;
    /// Animated twist of the mesh (engine lucent/mesh/Deform.h), display only. The posed mesh
    /// is re-uploaded every frame; the subsurface passes look the material up at the posed
    /// surface (small twists only). Painting is paused while it runs.
    bool deform = false;
    // SSLPV
    bool sslpvCalibrated = false;  ///< SslpvMode::Calibrated instead of Paper
    int sslpvGrid = 32;            ///< LPV cells per axis: 16, 32 or 64
    int sslpvSteps = 32;           ///< propagation steps, [1, 512]
    int sslpvOrder = 1;            ///< SH order 1 or 2
    bool sslpvGlSolve = false;     ///< propagation on the GPU (SslpvBackend::Gl)
    // Dipoles
    int dipoleSpp = 16;   ///< samples per pixel and frame, [1, 4096]; refines while idle
    int dirpoleSpp = 16;  ///< directional dipole: disc samples per texel and frame, [1, 4096]
    /// Combined: split radius r_s in mm (dipole for r ≤ r_s, SSLPV beyond); < 0 picks the
    /// module's default (4 SSLPV cells).
    float combinedSplitRadius = -1.f;
    /// Show only the subsurface term (debug view; gpu::DirectSettings::subsurfaceOnly).
    bool subsurfaceOnly = false;
    /// Reuse the G-buffer and the direct-lighting term while their inputs are unchanged
    /// (gpu::DirectSettings::reuseUnchangedPasses); false only to measure the gain.
    bool reusePasses = true;
    // Volume overlay (drawn over the tone-mapped image, inside the object's box only)
    bool volumeOverlay = false;   ///< ray-march the painted volume over the viewport
    int overlayChannel = 0;       ///< 0 σt, 1 σs′, 2 g (the slice view's colour maps)
    float overlayOpacity = 0.5f;  ///< overlay opacity in [0, 1]
};

/// Per-frame numbers for the Statistics dock.
struct PreviewStats {
    /// (pass, GPU ms, CPU ms) of the renderer's last collected frame.
    struct Pass {
        std::string name;
        double gpuMs = 0.0, cpuMs = 0.0;
    };
    std::vector<Pass> passes;
    std::string methodDetail;         ///< method-specific lines (SSLPV timings, dipole progress)
    int bricksUploaded = 0;           ///< bricks consumed by the last material update
    int sslpvIncrementalUpdates = 0;  ///< SSLPV updateMaterial calls that did work (dirty bricks)
    int sslpvFullResamples = 0;       ///< SSLPV setMaterial calls
    double uploadMs = 0.0;            ///< CPU ms of the last material update
    /// Frames since create() that reused the shadow maps, the G-buffer and the direct-lighting
    /// term (gpu::DirectSettings::reuseUnchangedPasses; a paint stroke reuses all three).
    long long shadowsReused = 0, gbufferReused = 0, directReused = 0;
};

/// What one frame needs. Positions in mm; the camera's width/height are the render size.
struct PreviewFrame {
    const Scene* scene = nullptr;
    MaterialVolume* volume = nullptr;         ///< the painted volume of object 0 (may be null)
    const TriangleMesh* shownMesh = nullptr;  ///< rest or posed mesh of object 0
    bool meshChanged = false;                 ///< shownMesh differs from the last frame's
    bool sceneReplaced = false;               ///< new scene: full re-synchronisation
    std::vector<int> dirtyBricks;             ///< painted since the last frame
    Camera camera;
    RenderSettings settings;
    std::optional<Point3f> cursor;  ///< brush cursor centre on the surface, mm
    float brushRadius = 0.f;        ///< mm
    unsigned framebuffer = 0;       ///< destination (Qt: defaultFramebufferObject())
    int framebufferWidth = 0, framebufferHeight = 0;
};

class PreviewRenderer {
public:
    PreviewRenderer();
    ~PreviewRenderer();
    PreviewRenderer(const PreviewRenderer&) = delete;
    PreviewRenderer& operator=(const PreviewRenderer&) = delete;

    /// Compiles every program (GL 4.5 core context current). @throw GpuError with file:line.
    void create();
    /// Frees every GL object (context current). Idempotent.
    void destroy();
    [[nodiscard]] bool isCreated() const;

    /// Renders one frame into frame.framebuffer (context current). @throw lucent::Error.
    void render(PreviewFrame& frame);
    /// True while a progressive method still refines (another frame is useful when idle).
    [[nodiscard]] bool wantsAnotherFrame() const;
    [[nodiscard]] const PreviewStats& stats() const;
    /// The last frame's linear radiance at render resolution (camera width × height),
    /// W/(mm²·sr), before tone mapping and overlays, top row first (for EXR export). Reads the
    /// GPU back on demand (context current). @throw lucent::Error before the first frame.
    [[nodiscard]] ImageRgb linearImage() const;
    /// Whether this build has `method` (DirectionalDipole and Combined depend on the modules).
    [[nodiscard]] static bool hasMethod(RenderSettings::Method method);
    /// The shaders every pass and provider is compiled from (embedded, or $LUCENT_SHADER_DIR).
    /// An in-memory file set here (ShaderLibrary::setFile) is used by the programs compiled
    /// after it, e.g. a provider created when its method is next selected.
    [[nodiscard]] gpu::ShaderLibrary& shaderLibrary();

private:
    struct Impl;
    std::unique_ptr<Impl> m;
};

}  // namespace lucent::app
