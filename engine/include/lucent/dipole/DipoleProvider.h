// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The image-space dipole (Mertens et al. 2005, seed 004) as a gpu::SubsurfaceProvider:
/// live, progressive subsurface radiance for gpu::SceneRenderer (CLI and Qt preview).
///
/// Per frame, with the renderer's context current:
///  1. (after a reset only) irradiance pass: per covered G-buffer pixel, the Fresnel-transmitted
///     irradiance E = Σ_lights F_t(η, cos θ_i) E⊥ cos θ_i V (seed 004 Eq. 5; V from the
///     renderer's shadow maps) and the painted material just inside the surface (the volume is a
///     3-D texture, re-uploaded brick by brick);
///  2. gather pass: one more set of samples of the dipole gather (same estimator as
///     gatherImageSpace(), a new Cranley–Patterson rotation per frame) added to a running sum;
///  3. resolve: L = F_t(η, ω_o) B̄/π (Eq. 3) into the renderer's subsurface texture.
/// Accumulation restarts when the camera, the lights, the material or the settings change (or on
/// reset()); it stops adding samples when the largest per-pixel change of the mean falls below
/// ProviderSettings::convergenceThreshold times the brightest pixel, or after maxFrames.
///
/// Usage (Qt: create in initializeGL, destroy on aboutToBeDestroyed, context current):
/// @code
///   dipole::DipoleSubsurfaceProvider dp;
///   dp.create();                                   // compiles the compute programs
///   int id = renderer.addMesh(mesh, {Rgb(0.f), Rgb(fresnelReflectance(1.0, eta)), 64.f});
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
    bool jacobian = true;        ///< GatherSettings::jacobian (Eq. 9)
    float maxJacobian = 8.f;     ///< GatherSettings::maxJacobian
    int interleave = 4;          ///< GatherSettings::interleave (k×k shift table)
    uint32_t seed = 1;           ///< frame 0 uses exactly gatherImageSpace()'s table for `seed`
    bool shadows = true;  ///< irradiance shadowed by the renderer's shadow maps (when it has them)
    /// SceneRenderer mesh id (addMesh's return) the material belongs to: other meshes (a ground
    /// plane) get no subsurface term and lend no irradiance to the gather. −1: every mesh.
    int meshId = -1;

    /// The CPU gather settings of frame 0 (importance = samplesPerFrame − uniform).
    [[nodiscard]] GatherSettings gatherSettings() const;
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
};

/// gpu::SubsurfaceProvider running the image-space dipole gather on the GPU, progressively.
/// Create/destroy explicitly with a current GL 4.5 context (the renderer's).
class DipoleSubsurfaceProvider final : public gpu::SubsurfaceProvider {
public:
    DipoleSubsurfaceProvider();
    ~DipoleSubsurfaceProvider() override;
    DipoleSubsurfaceProvider(const DipoleSubsurfaceProvider&) = delete;
    DipoleSubsurfaceProvider& operator=(const DipoleSubsurfaceProvider&) = delete;

    /// Compiles dipole_irradiance.comp and dipole_provider.comp (context current).
    /// @throw GpuError with file:line on shader errors.
    void create(const gpu::ShaderLibrary& library = gpu::ShaderLibrary());
    /// Frees every GL object (context current). Idempotent.
    void destroy();
    [[nodiscard]] bool isCreated() const;

    /// @throw ValueError naming the field (model dirpole, η ∉ [1,3], counts out of range).
    void setSettings(const ProviderSettings& settings);
    [[nodiscard]] const ProviderSettings& settings() const;

    /// The painted material (non-owning; must outlive its use, nullptr = none: black output).
    /// Its grid is in the mesh's space (mm). The whole volume is uploaded at the next frame.
    void setMaterial(const MaterialVolume* volume);
    /// Re-uploads bricks `bricks` of the attached volume (context current) and restarts the
    /// accumulation; for callers that share MaterialVolume::takeDirtyBricks() between passes.
    /// @throw ValueError for a brick index out of range or no attached volume.
    void uploadBricks(const std::vector<int>& bricks);
    /// setMaterial(&volume) if it is not attached, then uploadBricks(volume.takeDirtyBricks())
    /// when there are any (context current).
    void syncMaterial(MaterialVolume& volume);
    /// Restarts the accumulation (e.g. after updateMesh() on a deforming mesh: G-buffer content
    /// changes that the camera, lights and material do not reveal).
    void reset();

    [[nodiscard]] const ProviderStats& stats() const;
    /// GL names of the intermediate images (valid after a frame; for tests and debugging):
    /// RGBA32F irradiance E (W/mm²), σt and σs′ (mm⁻¹) per pixel, running sum of B (W/mm²),
    /// and the RGBA32F 3-D material textures (σt rgb + inside in a; σs′ rgb).
    struct DebugTextures {
        unsigned irradiance = 0, sigmaT = 0, sigmaS = 0, accumulation = 0;
        unsigned volumeSigmaT = 0, volumeSigmaS = 0;
    };
    [[nodiscard]] DebugTextures debugTextures() const;

    /// gpu::SubsurfaceProvider: one progressive step (see the file comment).
    void renderSubsurface(const gpu::GBufferView& gbuffer, unsigned targetTexture) override;

private:
    struct Impl;
    std::unique_ptr<Impl> m;
};

}  // namespace lucent::dipole
