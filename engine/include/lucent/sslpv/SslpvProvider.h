// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief SSLPV (Børlum et al. 2011, Børlum et al. 2011) as a gpu::SubsurfaceProvider: the live
/// preview while the artist paints. The CPU SslpvSolver (or SslpvGl for the propagation steps)
/// solves the light volume; the accumulation grid is uploaded to 3-D textures; a compute pass
/// (shaders/sslpv_sample.comp) evaluates at every covered G-buffer pixel exactly what the CPU
/// SslpvRenderer evaluates per ray hit: L_o = T(ω_o)·L_i with L_i from Eq. 5–7, read half a
/// cell (then 1, 1.5 cells) inside the surface, trilinear over inside cells
/// (SslpvSolver::radiance), and T = 1 − F_r(cos θ_o, η) (Eq. 4).
///
/// Usage (Qt: create in initializeGL, destroy on aboutToBeDestroyed, context current):
/// @code
///   SslpvSubsurfaceProvider sp(options);        // no GL yet
///   sp.create();                                // compiles sslpv_sample.comp (context current)
///   sp.setMesh(mesh);  sp.setLights(lights);    // rest space, mm: re-injection
///   sp.setMaterial(volume, eta);                // full resample (once, or on a new volume)
///   renderer.setSubsurfaceProvider(&sp);
///   // per stroke (after the brush wrote the volume):
///   sp.updateMaterial(volume, volume.takeDirtyBricks());  // incremental resample
///   renderer.render();                          // solve + upload + sample when dirty
///   sp.timings();                               // per-pass ms for the statistics panel
///   renderer.setSubsurfaceProvider(nullptr);  sp.destroy();
/// @endcode
/// The RSM injection texels come from an internal SslpvRenderer (the same code as the CPU
/// image path), so CPU and GL use identical inputs. Units: mm, W/sr, radiance W/(mm²·sr).

#include <lucent/core/Types.h>
#include <lucent/gpu/SceneRenderer.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/material/Resample.h>
#include <lucent/mesh/TriangleMesh.h>
#include <lucent/scene/Scene.h>
#include <lucent/sslpv/SslpvGl.h>
#include <lucent/sslpv/SslpvRenderer.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <memory>
#include <vector>

namespace lucent::sslpv {

/// Where the propagation steps run.
enum class SslpvBackend {
    Cpu,  ///< SslpvSolver (injection and propagation on the CPU)
    Gl,   ///< SslpvSolver injects and folds factors, SslpvGlPropagator runs the steps
};

/// Provider settings. Solver/grid/injection changes mark the matching stage dirty.
struct SslpvProviderOptions {
    /// Solver settings, gridResolution and injectionResolution are used (the shading fields
    /// subsurface/direct/specular/diffuse belong to the CPU image and are ignored).
    SslpvRenderOptions render;
    SslpvBackend backend = SslpvBackend::Cpu;
    SslpvGlStorage glStorage = SslpvGlStorage::Float32;  ///< Gl backend grid precision
    int meshId = 0;  ///< SceneRenderer mesh id the term is written for; −1: every covered pixel
    /// Live refinement (modes Paper and Calibrated): a change's frame propagates
    /// render.solver.maxSteps steps; while light is still in flight after them, each later
    /// frame with nothing else to do carries the propagation on by as many steps
    /// (SslpvSolver::continuePropagation: the steps one longer solve would run), until the stop
    /// rules end it or refineSteps steps in all. 0 (or ≤ maxSteps): off, a change's frame is
    /// the last. [0, 4096].
    int refineSteps = 0;
};

/// The solver options a live propagation ends with: render.solver with maxSteps raised to
/// refineSteps when refinement is on (refine() carries a change's propagation on to them, and
/// SslpvSolver::continuePropagation runs the steps of that one longer solve). What a local
/// model of the converged picture (combined's kernel) is computed with.
[[nodiscard]] SslpvOptions refinedSolverOptions(const SslpvProviderOptions& options);

/// Per-pass milliseconds of the last work done for each pass (CPU wall time unless stated).
struct SslpvProviderTimings {
    double resampleMs = 0.0;    ///< last setMaterial (full) or updateMaterial (incremental)
    double rsmMs = 0.0;         ///< reflective shadow maps (lights/mesh changed)
    double injectMs = 0.0;      ///< injection (§3.1)
    double propagateMs = 0.0;   ///< propagation (§3.2): CPU solver, or GL CPU-issue + wait
    double uploadMs = 0.0;      ///< accumulation grid → 3-D textures
    double sampleCpuMs = 0.0;   ///< issuing the per-pixel sample pass
    double sampleGpuMs = 0.0;   ///< GPU time of the sample pass (GL_TIME_ELAPSED, 1 frame late)
    double lastUpdateMs = 0.0;  ///< resample + rsm + inject + propagate + upload of last change
};

/// Counters for tests and the statistics panel.
struct SslpvProviderStats {
    int fullResamples = 0;          ///< setMaterial calls (resampleForPropagation)
    int incrementalUpdates = 0;     ///< updateMaterial calls with at least one dirty brick
    size_t lastResampledCells = 0;  ///< coarse cells recomputed by the last (partial) resample
    /// Material updates written into the solver's material cell by cell (strokes that kept
    /// the shape: SslpvSolver::markMaterialCellsDirty) instead of handing it a new one.
    int inPlaceUpdates = 0;
    int solves = 0;       ///< solver runs that did work
    int refinements = 0;  ///< frames that carried the propagation on (refineSteps)
    int uploads = 0;      ///< grid uploads
    int frames = 0;       ///< sample passes
};

/// gpu::SubsurfaceProvider evaluating SSLPV per G-buffer pixel. Create/destroy explicitly with
/// a current GL 4.5 context (the renderer's); the CPU side (set*, update()) needs no context.
class SslpvSubsurfaceProvider final : public gpu::SubsurfaceProvider {
public:
    /// @throw ValueError for options out of range.
    explicit SslpvSubsurfaceProvider(const SslpvProviderOptions& options = {});
    ~SslpvSubsurfaceProvider() override;
    SslpvSubsurfaceProvider(const SslpvSubsurfaceProvider&) = delete;
    SslpvSubsurfaceProvider& operator=(const SslpvSubsurfaceProvider&) = delete;

    /// Compiles the sample program (and the GL propagator for the Gl backend). Context current.
    /// @throw GpuError on shader errors.
    void create(const gpu::ShaderLibrary& library);
    /// create() with the embedded shaders (or $LUCENT_SHADER_DIR).
    void create();
    /// Frees every GL object (context current). Idempotent.
    void destroy();
    [[nodiscard]] bool isCreated() const;

    //! @{ \name Live inputs
    /// @throw ValueError for options out of range. Switching to the Gl backend needs create()
    /// again (or is picked up at the next frame when created). A new gridResolution drops the
    /// material (the coarse grid is resampled from the fine volume, which the provider does not
    /// keep): call setMaterial() or updateMaterial() again before the next frame
    /// (hasMaterial() says whether one is needed).
    void setOptions(const SslpvProviderOptions& options);
    [[nodiscard]] const SslpvProviderOptions& options() const;
    /// The object's rest-space mesh (mm): rebuilds the RSM ray caster and the inside mask,
    /// re-injects. @throw ValueError for an empty mesh.
    void setMesh(const TriangleMesh& mesh);
    /// Lights changed: re-injection only.
    void setLights(const std::vector<Light>& lights);
    /// World → rest space of the object (identity by default; rigid transforms only, the
    /// G-buffer's world positions and normals are mapped back with it).
    /// @throw ValueError for a non-finite or non-invertible matrix.
    void setObjectFromWorld(const Mat4f& objectFromWorld);
    /// New or replaced volume: full resampleForPropagation to gridResolution³, re-propagation
    /// (re-injection too when the grid moved). @param eta relative index, [1, 3].
    /// @throw ValueError for eta out of range or an empty volume.
    void setMaterial(const MaterialVolume& volume, float eta);
    /// Whether a material is set for the current gridResolution (update() and
    /// renderSubsurface() throw without one).
    [[nodiscard]] bool hasMaterial() const;
    /// Painted bricks (e.g. volume.takeDirtyBricks()): updateCoarseMaterial on the coarse
    /// cells they overlap, then re-propagation. Falls back to setMaterial() (η of the last
    /// setMaterial, else volume.eta()) when no material was set, the volume's grid or
    /// gridResolution changed. Bit-identical to a from-scratch setMaterial().
    void updateMaterial(const MaterialVolume& volume, const std::vector<int>& dirtyBricks);
    //! @}

    /// Runs the CPU stages that are dirty (inside mask, RSM, injection, propagation on the
    /// CPU backend). renderSubsurface() calls it; call it directly for CPU-only use.
    /// @throw ValueError if the mesh or material is missing.
    const SslpvStats& update();
    /// True when update() or the upload has work to do.
    [[nodiscard]] bool isDirty() const;
    /// Live refinement (SslpvProviderOptions::refineSteps): when nothing is dirty and the last
    /// propagation stopped with light in flight, carries it on by render.solver.maxSteps steps
    /// (at most up to refineSteps in all). renderSubsurface() calls it on a frame that had no
    /// change to solve. Returns whether it propagated.
    bool refine();
    /// False while refine() would carry the propagation on (another frame changes the image).
    [[nodiscard]] bool converged() const;

    /// gpu::SubsurfaceProvider: update(), GL propagation (Gl backend), upload when changed,
    /// then the per-pixel sample pass into `targetTexture`. Context current.
    void renderSubsurface(const gpu::GBufferView& gbuffer, unsigned targetTexture) override;
    /// An RGBA32F texture of the G-buffer's size into which the sample pass of mode diffusion
    /// also writes the albedo its read-out sees at every pixel it writes (rgb: α′ per
    /// channel, SslpvSolver::readoutAlbedo; 0 where no cell is read); 0 (the default): none.
    /// The propagation modes hold no albedo and leave the texture as it is.
    void setAlbedoOutput(unsigned texture);

    //! @{ \name Results
    [[nodiscard]] const SslpvSolver& solver() const;
    /// The grid sampled by the GL pass: the solver's accumulation (Cpu) or the GL result.
    [[nodiscard]] const SslpvGrid& accumulation() const;
    /// The unmasked coarse material kept up to date incrementally.
    [[nodiscard]] const CoarseMaterial& coarseMaterial() const;
    [[nodiscard]] float eta() const;
    [[nodiscard]] const SslpvProviderTimings& timings() const;
    [[nodiscard]] const SslpvProviderStats& stats() const;
    //! @}

private:
    struct Impl;
    std::unique_ptr<Impl> m;
};

}  // namespace lucent::sslpv
