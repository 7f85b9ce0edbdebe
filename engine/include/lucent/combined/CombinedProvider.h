// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The combined mode (lucent/combined/Combined.h) as a gpu::SubsurfaceProvider: owns an
/// SslpvSubsurfaceProvider (late steps, skip k) and a dipole::DipoleSubsurfaceProvider (window
/// r ≤ r_s), runs both per frame and sums their outputs into the renderer's target
/// (shaders/combined_add.comp). Material changes are taken once and handed to both.
///
/// Usage (Qt: create in initializeGL, destroy on aboutToBeDestroyed, context current):
/// @code
///   combined::CombinedSubsurfaceProvider cp;           // no GL yet
///   cp.create();                                        // both providers + the add program
///   int id = renderer.addMesh(mesh);
///   combined::CombinedProviderSettings s;  s.meshId = id;  s.eta = scene.eta;
///   cp.setSettings(s);
///   cp.setMesh(mesh);  cp.setLights(lights);  cp.setMaterial(volume, scene.eta);
///   renderer.setSubsurfaceProvider(&cp);
///   // per stroke: cp.syncMaterial(volume);              // takeDirtyBricks() once, both passes
///   renderer.render();  if (!cp.stats().converged) scheduleNextFrame();
///   renderer.setSubsurfaceProvider(nullptr);  cp.destroy();
/// @endcode
/// Units: mm, W/sr, radiance W/(mm²·sr).

#include <lucent/combined/Combined.h>
#include <lucent/dipole/DipoleProvider.h>
#include <lucent/gpu/GpuTimer.h>
#include <lucent/gpu/SceneRenderer.h>
#include <lucent/sslpv/SslpvProvider.h>

#include <memory>
#include <vector>

namespace lucent::combined {

/// dipole::ProviderSettings with the light-view images off (the combined mode's default).
inline dipole::ProviderSettings cameraOnlyDipole() {
    dipole::ProviderSettings s;
    s.lightViews = false;
    return s;
}

/// Settings of the combined provider. Changing the split restarts the dipole accumulation and
/// re-propagates SSLPV.
struct CombinedProviderSettings {
    float splitRadius = -1.f;  ///< r_s, mm (CombinedSettings::splitRadius semantics)
    SplitMode mode = SplitMode::Kernel;
    int localSamples = 32;  ///< Kernel mode: disc samples of SSLPV's local estimate, [1, 4096]
    /// The automatic SSLPV skip (CombinedSettings::autoSkipSslpv, applyFarSkip): decided from
    /// the attached mesh's extent and material when either or the settings change, and again
    /// after a stroke.
    bool autoSkipSslpv = true;
    float farTolerance = DEFAULT_FAR_TOLERANCE;  ///< ≥ 0 (CombinedSettings::farTolerance)
    float eta = 1.3f;                            ///< relative index, [1, 3] (both providers)
    int meshId = 0;  ///< SceneRenderer mesh id of the object (both providers)
    /// Dipole provider settings (model, samples per frame...); eta, meshId and maxRadius are
    /// overwritten from the fields above and the split. Light views are off by default: the
    /// local-part subtraction sees the camera image only, so light-view irradiance gathered by
    /// the dipole would be counted twice (docs/methods/combined.md).
    dipole::ProviderSettings dipole = cameraOnlyDipole();
    /// SSLPV provider options (grid, steps, mode); skipAccumulateSteps is k₀, raised to k.
    sslpv::SslpvProviderOptions sslpv{.render = CombinedSettings::defaultSslpvOptions()};
};

/// Progressive state of both parts.
struct CombinedProviderStats {
    dipole::ProviderStats dipole;     ///< accumulation of the dipole part
    sslpv::SslpvProviderStats sslpv;  ///< solves/uploads of the SSLPV part
    SplitPlan plan;                   ///< the split in use (valid once a material is set)
    int frames = 0;                   ///< renderSubsurface calls
    /// the dipole part converged (SSLPV is deterministic) and the kernel is up to date (a
    /// stroke's kernel update runs at the frame after the stroke's)
    bool converged = false;
    int localEstimates = 0;  ///< Kernel split: computations of the local SSLPV estimate L̂
    /// Kernel split: strokes after which the kernel (and L̂) was kept because the mean material
    /// of the volume's surface cells stayed within KERNEL_MATERIAL_TOLERANCE of the kernel's.
    int kernelsKept = 0;
};

/// A stroke moves the mean material of the volume's surface cells (surfaceMaterial), which
/// SSLPV's local kernel is computed for; the
/// kernel (and with it L̂, 57 ms at 640×360 on llvmpipe) is recomputed only when the mean's σa,
/// σs′ (relative, per channel) or g (absolute) has moved by more than this since the kernel's.
constexpr float KERNEL_MATERIAL_TOLERANCE = 0.01f;

/// Whether `now` is within KERNEL_MATERIAL_TOLERANCE of `was` (see there).
[[nodiscard]] bool kernelMaterialClose(const MaterialSample& now, const MaterialSample& was);

/// gpu::SubsurfaceProvider summing the windowed dipole and SSLPV (minus its local kernel part in
/// the Kernel split, or without its first k steps in the Steps split).
class CombinedSubsurfaceProvider final : public gpu::SubsurfaceProvider {
public:
    CombinedSubsurfaceProvider();
    ~CombinedSubsurfaceProvider() override;
    CombinedSubsurfaceProvider(const CombinedSubsurfaceProvider&) = delete;
    CombinedSubsurfaceProvider& operator=(const CombinedSubsurfaceProvider&) = delete;

    /// Creates both providers and compiles combined_add.comp (context current).
    /// @throw GpuError on shader errors.
    void create(const gpu::ShaderLibrary& library = gpu::ShaderLibrary());
    /// Frees every GL object (context current). Idempotent.
    void destroy();
    [[nodiscard]] bool isCreated() const;

    /// @throw ValueError naming the field (η ∉ [1, 3], NaN split, provider settings).
    void setSettings(const CombinedProviderSettings& settings);
    [[nodiscard]] const CombinedProviderSettings& settings() const;

    //! @{ \name Live inputs (forwarded)
    /// Rest-space mesh (mm) for SSLPV's RSM and inside mask. @throw ValueError for an empty mesh.
    void setMesh(const TriangleMesh& mesh);
    void setLights(const std::vector<Light>& lights);
    /// @throw ValueError as SslpvSubsurfaceProvider::setObjectFromWorld.
    void setObjectFromWorld(const Mat4f& objectFromWorld);
    /// New volume (non-owning for the dipole part: must outlive its use): full resample for
    /// SSLPV, full upload for the dipole at the next frame; fixes Δx and so the split.
    /// @throw ValueError for η ∉ [1, 3] or an empty volume.
    void setMaterial(const MaterialVolume& volume, float eta);
    /// After painting: takes volume.takeDirtyBricks() once and hands the same list to both
    /// parts (SSLPV incremental resample now, dipole brick upload at the next frame).
    /// @return the number of dirty bricks taken.
    size_t syncMaterial(MaterialVolume& volume);
    /// The same with bricks the caller already took (shared with other consumers).
    void updateMaterial(const MaterialVolume& volume, const std::vector<int>& dirtyBricks);
    //! @}

    /// gpu::SubsurfaceProvider: SSLPV into the target, the dipole into a scratch image, then
    /// target = max(0, target + scratch − min(L̂, f·target)) (Kernel split; L̂ and f
    /// reads the dipole part's irradiance image) or target += scratch (Steps). Context current.
    void renderSubsurface(const gpu::GBufferView& gbuffer, unsigned targetTexture) override;

    [[nodiscard]] const CombinedProviderStats& stats() const;
    /// GPU and CPU time of the parts ("sslpv", "dipole", "kernel", "add") in the most recent
    /// frame whose timer queries are available (context current: may wait for the last frame).
    [[nodiscard]] std::vector<gpu::PassTiming> passTimes() const;
    //! @{ \name The parts (for tests, timings and the statistics panel)
    [[nodiscard]] const sslpv::SslpvSubsurfaceProvider& sslpvProvider() const;
    [[nodiscard]] const dipole::DipoleSubsurfaceProvider& dipoleProvider() const;
    /// Kernel split: SSLPV's local kernel of the last frame, solved for kernelMaterial().
    [[nodiscard]] const SslpvSurfaceKernel& kernel() const;
    /// The mean material of the volume's surface cells the kernel was solved for (surfaceMaterial).
    [[nodiscard]] const MaterialSample& kernelMaterial() const;
    /// The outside cosine the kernel was lit at: meanIncidenceCosine of the mesh and lights
    /// when it was solved (a light that moves it by a step has the next frame solve it again).
    [[nodiscard]] float kernelIncidence() const;
    //! @}

private:
    void applySplit();
    /// L̂ into the `local` image when anything it depends on changed (Kernel split).
    void updateLocalEstimate(const gpu::GBufferView& g);
    struct Impl;
    std::unique_ptr<Impl> m;
};

}  // namespace lucent::combined
