// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The image-space dipole (Mertens et al. 2005) as a gpu::SubsurfaceProvider:
/// live, progressive subsurface radiance for gpu::SceneRenderer (CLI and Qt preview).
///
/// Per frame, with the renderer's context current:
///  1. (after a reset only) irradiance pass: per covered G-buffer pixel, the Fresnel-transmitted
///     irradiance E = Σ_lights F_t(η, cos θ_i) E⊥ cos θ_i V (Mertens et al. 2005 Eq. 5; V from the
///     renderer's shadow maps) and the painted material just inside the surface (the volume is a
///     3-D texture, re-uploaded brick by brick); then the light views (§7.1: the object
///     rasterised from each light and its E, kept while meshes, lights and shadow maps are
///     unchanged; each view's back-lit flux fraction, redone per reset), gathered when back-lit
///     (ProviderSettings::lightViews);
///  2. gather pass: one more set of samples of the dipole gather (same estimator as
///     gatherImageSpace(), a new Cranley–Patterson rotation per frame) added to a running sum;
///  3. resolve: L = F_t(η, ω_o) B̄/π (Eq. 3) into the renderer's subsurface texture.
/// Accumulation restarts when the camera, the lights, the meshes or the settings change (or on
/// reset()); it stops adding samples when the largest per-pixel change of the mean falls below
/// ProviderSettings::convergenceThreshold times the brightest pixel, or after maxFrames. A
/// restart while an image is shown is bounded (ProviderSettings::previewSamples): a camera-only
/// preview first, the light views' work spread over the following frames. A material change
/// (a paint stroke) restarts only the pixels whose material changed, which then catch up to the
/// others' frame count (a pixel's sum depends on the material only through its own σt, σs′).
///
/// Usage (Qt: create in initializeGL, destroy on aboutToBeDestroyed, context current):
/// @code
///   dipole::DipoleSubsurfaceProvider dp;
///   dp.create();                                   // compiles the compute programs
///   int id = renderer.addMesh(mesh, {Rgb(0.f), Rgb(fresnelDielectric(1.0, eta)), 64.f});
///   dipole::ProviderSettings ps; ps.model = Model::BetterDipole; ps.eta = eta; ps.meshId = id;
///   dp.setSettings(ps);
///   dp.setMaterial(&volume);                       // non-owning; full upload at the next frame
///   renderer.setSubsurfaceProvider(&dp);
///   // each frame: dp.syncMaterial(volume) after painting (uploads only the dirty bricks)
///   renderer.render();  if (!dp.stats().converged) scheduleNextFrame();
///   renderer.setSubsurfaceProvider(nullptr);  dp.destroy();
/// @endcode
/// Units: mm, mm⁻¹, irradiance/exitance W/mm², radiance W/(mm²·sr).

#include <lucent/dipole/ImageSpace.h>
#include <lucent/gpu/SceneRenderer.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace lucent {
class MaterialVolume;
}

namespace lucent::dipole {

/// Settings of the provider. Changing any of them restarts the accumulation.
struct ProviderSettings {
    Model model = Model::Dipole;  ///< Dipole or BetterDipole
    float eta = 1.3f;             ///< relative index of the object, [1, 3]
    int samplesPerFrame = 16;     ///< per pixel and frame, [1, 4096]; ¼ uniform disc samples
    int maxFrames = 256;          ///< accumulation stops after this many frames, [1, 1e6]
    /// Stop when max_pixels |B̄_N − B̄_{N−1}| < this × max_pixels B̄_N (per channel), [0, 1).
    float convergenceThreshold = 1e-3f;
    float discQuantile = 0.99f;  ///< GatherSettings::discQuantile
    float maxRadius = 0.f;  ///< mm; > 0: the gather only integrates r ≤ maxRadius (0 = unlimited)
    bool jacobian = true;   ///< GatherSettings::jacobian (Eq. 9)
    float maxJacobian = 8.f;  ///< GatherSettings::maxJacobian
    int interleave = 4;       ///< GatherSettings::interleave (k×k shift table)
    uint32_t seed = 1;        ///< frame 0 uses exactly gatherImageSpace()'s table for `seed`
    bool shadows = true;  ///< irradiance shadowed by the renderer's shadow maps (when it has them)
    /// SceneRenderer mesh id (addMesh's return) the material belongs to: other meshes (a ground
    /// plane) get no subsurface term and lend no irradiance to the gather. −1: every mesh.
    int meshId = -1;
    /// Light-view irradiance images (Mertens et al. 2005 §7.1, docs/methods/dipole.md §3d): after a
    /// reset, the object is rasterised from each light (lightViewCamera()), its E computed like the
    /// camera's, and the view is gathered with the camera's (balance heuristic; the views share
    /// samplesPerFrame, viewSamples()) when its back-lit flux fraction exceeds
    /// lightViewThreshold; false: the camera image only.
    bool lightViews = true;
    int lightViewResolution = 512;     ///< texels per side of a light view, [16, 4096]
    float lightViewThreshold = 1e-3f;  ///< LightViewSettings::threshold, [0, 1)
    /// Interactive restarts (docs/methods/dipole.md §3c "Bounded restarts"), [0, 4096]: a restart
    /// that discards a shown image (not the first frame after create()) first draws one
    /// *preview* frame: the camera image only, this many samples per pixel, not accumulated.
    /// The next frames bring the light views up to date (at most one re-rendered view or the
    /// back-lit-fraction pass per frame, the preview staying on screen); then the full
    /// estimator accumulates exactly as after a restart with previewSamples = 0, its frames
    /// split into ProviderStats::frameParts parts. Camera-only and light-view frames are never
    /// mixed (that would be biased). 0: every restart computes everything in its first frame.
    int previewSamples = 4;
    /// The live preview (the app): the first accumulation after create() is bounded like every
    /// later restart (a preview, the light views over the next frames, then frames in parts),
    /// so a method switch never blocks on one whole frame (≈ 200 ms at 640×360 with two light
    /// views on llvmpipe). false (the CLI, `evaluate`): the first frame computes everything and
    /// is exactly gatherImageSpace()'s. Needs previewSamples > 0; no restart when it changes.
    bool interactiveFirstFrame = false;

    /// The CPU gather settings of frame 0 (importance = samplesPerFrame − uniform).
    [[nodiscard]] GatherSettings gatherSettings() const;

    bool operator==(const ProviderSettings&) const = default;
};

/// State of the progressive accumulation.
struct ProviderStats {
    int frames = 0;            ///< frames accumulated since the last reset
    int samplesPerPixel = 0;   ///< frames × samplesPerFrame
    float lastChange = 1.f;    ///< max |ΔB̄| / max B̄ of the last accumulated frame
    bool converged = false;    ///< no more samples are added until something changes
    int resets = 0;            ///< accumulation restarts so far
    int lastUploadBricks = 0;  ///< bricks written by the last material upload
    int fullUploads = 0;       ///< complete volume uploads so far
    // Set at each reset (the irradiance passes; a material-only restart widens the R′ range by
    // its restarted pixels, it does not narrow it):
    float epsilon = 0.f;         ///< 1 − discQuantile: energy fraction beyond R′ (GatherStats)
    float minRadius = 0.f;       ///< disc radius min(R′, maxRadius) over the object's pixels, mm
    float maxRadius = 0.f;       ///< (0 when no object pixel)
    int lightViewsRendered = 0;  ///< light views rendered
    int lightViewsGathered = 0;  ///< of which gathered (back-lit fraction > threshold)
    /// Per light: backlitFluxFraction() of its view; −1 when none was rendered (light views
    /// off, or the light inside the object's bounding sphere).
    std::vector<float> backlitFractions;
    /// Light views rasterised and lit (E) since create(). Views are kept while the meshes, the
    /// lights, the shadow setting and the view settings (η, resolution, meshId) are unchanged: a
    /// camera or material change re-renders none (only their back-lit fractions are redone).
    int lightViewPasses = 0;
    int previewFrames = 0;      ///< preview frames drawn since create() (ProviderSettings)
    bool preview = false;       ///< the last frame showed the preview or camera-only estimate
    bool viewsPending = false;  ///< light views or their fractions are still being updated
    /// Provider frames (dispatches) per accumulated frame: 1, or in an accumulation that began
    /// with an interactive restart ⌈pixels × samplesPerFrame × (1 + gathered views) /
    /// (320·180·16)⌉ (bounded idle frames; every pixel gets the samples of one frame either way).
    int frameParts = 1;
    /// Material-only restarts (docs/methods/dipole.md §3c): pixels whose material changed at the
    /// last material update (their sums restarted; the others kept theirs), and the pixels
    /// still catching up to the accumulation's frame count (0: none).
    int pixelsRestarted = 0;
    int pixelsCatchingUp = 0;
    /// Pixels whose material the last material update looked up again: those within the
    /// look-up's reach of a brick written since the update before (the others cannot change).
    int pixelsLookedUp = 0;
    /// GPU time (ms, GL timer queries) of the provider's passes in the last frame; 0 for a pass
    /// that did not run.
    struct PassTimes {
        float irradiance = 0.f;      ///< camera irradiance, material and R′ (after a reset)
        float lightViews = 0.f;      ///< light-view raster + E (re-rendered views only)
        float fractions = 0.f;       ///< back-lit fractions of the views
        float gather = 0.f;          ///< gather + resolve
        float materialUpdate = 0.f;  ///< material-only restart: the changed pixels found
    } passMs;
};

namespace detail {
class VolumeTextures;
}

/// What the GL dipole providers (DipoleSubsurfaceProvider, DirpoleSubsurfaceProvider) share:
/// the painted material, uploaded as 3-D textures brick by brick, and the progressive
/// accumulation's statistics. Every material change restarts the accumulation.
class MaterialSubsurfaceProvider : public gpu::SubsurfaceProvider {
public:
    ~MaterialSubsurfaceProvider() override;
    MaterialSubsurfaceProvider(const MaterialSubsurfaceProvider&) = delete;
    MaterialSubsurfaceProvider& operator=(const MaterialSubsurfaceProvider&) = delete;

    /// Compiles the provider's shaders and creates its GL objects (context current; the
    /// renderer's). @throw GpuError with file:line on shader errors (nothing stays allocated).
    void create(const gpu::ShaderLibrary& library = gpu::ShaderLibrary());
    /// Frees every GL object (context current). Idempotent.
    void destroy();
    [[nodiscard]] bool isCreated() const { return m_created; }

    /// The painted material (non-owning; must outlive its use, nullptr = none: black output).
    /// Its grid is in the mesh's space (mm). The whole volume is uploaded at the next frame.
    void setMaterial(const MaterialVolume* volume);
    /// Re-uploads bricks `bricks` of the attached volume (context current) and restarts the
    /// accumulation; for callers that share MaterialVolume::takeDirtyBricks() between passes.
    /// @throw ValueError before create(), for a brick index out of range or no attached volume.
    void uploadBricks(const std::vector<int>& bricks);
    /// setMaterial(&volume) if it is not attached, then uploadBricks(volume.takeDirtyBricks())
    /// when there are any (context current).
    void syncMaterial(MaterialVolume& volume);
    /// Restarts the accumulation (e.g. after updateMesh() on a deforming mesh: G-buffer content
    /// changes that the camera, lights and material do not reveal) and drops cached
    /// mesh-dependent data (the dipole provider's light views).
    void reset();
    [[nodiscard]] const ProviderStats& stats() const { return m_stats; }

protected:
    /// @param name the provider's class name, for error messages.
    explicit MaterialSubsurfaceProvider(const char* name);
    /// Restarts the accumulation at the next frame (each provider's rule).
    virtual void restart() = 0;
    /// reset() calls this before restart(): drop caches of anything derived from the G-buffer
    /// or the meshes (default: nothing cached).
    virtual void invalidateCaches() {}
    /// The provider's programs and GL objects; on a throw, destroyGl() frees what was made.
    virtual void createGl(const gpu::ShaderLibrary& library) = 0;
    /// Frees them (must accept a partly created state).
    virtual void destroyGl() = 0;
    /// @throw ValueError "<name>::<what> before create()" unless created.
    void requireCreated(const char* what) const;

    bool m_created = false;
    ProviderStats m_stats;
    std::unique_ptr<detail::VolumeTextures> m_volume;  ///< the material's 3-D textures
};

/// gpu::SubsurfaceProvider running the image-space dipole gather on the GPU, progressively.
/// Create/destroy explicitly with a current GL 4.5 context (the renderer's).
class DipoleSubsurfaceProvider final : public MaterialSubsurfaceProvider {
public:
    DipoleSubsurfaceProvider();
    ~DipoleSubsurfaceProvider() override;
    DipoleSubsurfaceProvider(const DipoleSubsurfaceProvider&) = delete;
    DipoleSubsurfaceProvider& operator=(const DipoleSubsurfaceProvider&) = delete;

    /// @throw ValueError naming the field (model dirpole, η ∉ [1,3], counts out of range).
    void setSettings(const ProviderSettings& settings);
    [[nodiscard]] const ProviderSettings& settings() const;

    /// GL names of the intermediate images (valid after a frame; for tests and debugging, and
    /// σt′, σs′ for the combined provider's add pass): RGBA32F irradiance E (W/mm²), reduced σt′
    /// and σs′ (mm⁻¹) per pixel, running sum of B (W/mm²), and the RGBA32F 3-D material textures
    /// (σt′ rgb + inside in a; σs′ rgb).
    struct DebugTextures {
        unsigned irradiance = 0, sigmaT = 0, sigmaS = 0, accumulation = 0;
        unsigned volumeSigmaT = 0, volumeSigmaS = 0;
    };
    [[nodiscard]] DebugTextures debugTextures() const;
    /// The light views the last reset gathered, read back as CPU buffers (context current; for
    /// the parity test: gatherImageSpace(camera, debugLightViews(), settings().gatherSettings())
    /// is frame 0). Material entries are left empty (the gather uses x_o's material).
    [[nodiscard]] std::vector<SurfaceBuffers> debugLightViews() const;

    /// gpu::SubsurfaceProvider: one progressive step (see the file comment).
    void renderSubsurface(const gpu::GBufferView& gbuffer, unsigned targetTexture) override;

private:
    void restart() override;
    void invalidateCaches() override;
    /// Compiles dipole_irradiance.comp, dipole_provider.comp (two variants), the light-view
    /// G-buffer (dirpole_gbuffer.*) and dipole_lightview.comp.
    void createGl(const gpu::ShaderLibrary& library) override;
    void destroyGl() override;
    struct Impl;
    std::unique_ptr<Impl> m;
};

}  // namespace lucent::dipole
