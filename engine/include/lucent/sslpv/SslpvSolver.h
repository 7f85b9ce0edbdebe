// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Subsurface Light Propagation Volumes on the CPU (Børlum et al. 2011, Børlum et al. 2011):
/// injection of refracted light (§3.1, Eq. 1), iterative propagation with absorption and
/// scattering (§3.2, Eq. 2–3), exitant-flux sinks, and the area-light radiance estimate of
/// §3.3 (Eq. 5–7). Incremental: the app sets what changed and calls solve().
///
///     SslpvSolver solver({.order = 1, .maxSteps = 32});
///     solver.setMaterial(resampleForPropagation(volume, 32), /*eta=*/1.3f);  // re-propagates
///     solver.setInjectionSamples(rsmTexels);                                 // re-injects
///     const SslpvStats& st = solver.solve();          // no-op when nothing is dirty
///     Rgb L = solver.radiance(p, n);                  // W/(mm²·sr), before Fresnel
///
/// Units: positions mm, σ mm⁻¹, SH coefficients of point-light intensities W/sr, flux W.
/// Grids are cell-centred on the material's GridSpec (docs/conventions.md).

#include <lucent/core/SphericalHarmonics.h>
#include <lucent/core/Types.h>
#include <lucent/material/Resample.h>
#include <lucent/sslpv/GridDiffusion.h>
#include <lucent/sslpv/Transfer.h>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace lucent::dipole {
class DirpoleExitTable;
}  // namespace lucent::dipole

namespace lucent::sslpv {

/// Dense SH grid, structure of arrays: one plane per (channel, coefficient), each a
/// (N+2)³ array with a one-cell zero border (x fastest) so the propagation stencil needs no
/// bounds tests. Coefficients are SH of point-light intensity in W/sr (orthonormal basis).
class SslpvGrid {
public:
    static constexpr int CHANNELS = 3;

    SslpvGrid() = default;
    /// @param resolution cells per axis (≥ 1). @param order 1 or 2.
    SslpvGrid(int resolution, int order);

    [[nodiscard]] int resolution() const { return m_res; }
    [[nodiscard]] int order() const { return m_order; }
    [[nodiscard]] int coeffCount() const { return m_coeffs; }
    /// Padded edge length N+2.
    [[nodiscard]] int paddedResolution() const { return m_res + 2; }
    [[nodiscard]] size_t planeSize() const { return m_planeSize; }
    /// Padded linear index of interior cell c ∈ [0,N)³.
    [[nodiscard]] size_t index(const Coord& c) const {
        const size_t p = size_t(m_res + 2);
        return (size_t(c.z + 1) * p + size_t(c.y + 1)) * p + size_t(c.x + 1);
    }
    float* plane(int channel, int coeff) { return &m_data[planeOffset(channel, coeff)]; }
    [[nodiscard]] const float* plane(int channel, int coeff) const {
        return &m_data[planeOffset(channel, coeff)];
    }
    /// Coefficient `coeff` of channel `channel` at interior cell c.
    [[nodiscard]] float at(const Coord& c, int channel, int coeff) const {
        return plane(channel, coeff)[index(c)];
    }
    void clear();
    /// Total flux Σ_cells ∫ I dω = 2√π Σ c00 per channel, W.
    [[nodiscard]] Rgb flux() const;
    /// Largest |coefficient| over the grid (NaN propagates as NaN).
    [[nodiscard]] float maxAbs() const;
    /// True when every value is finite.
    [[nodiscard]] bool isFinite() const;
    [[nodiscard]] const std::vector<float>& raw() const { return m_data; }
    std::vector<float>& raw() { return m_data; }

private:
    [[nodiscard]] size_t planeOffset(int channel, int coeff) const {
        return (size_t(channel) * m_coeffs + coeff) * m_planeSize;
    }
    int m_res = 0;
    int m_order = 1;
    int m_coeffs = 4;
    size_t m_planeSize = 0;
    std::vector<float> m_data;
};

/// What the Beer attenuation of §3.2.1 uses.
enum class SslpvAttenuation {
    Extinction,  ///< exp(−σt·Δx), σt = σa + σs′: the paper, literally (§3.2.1)
    Absorption,  ///< exp(−σa·Δx), σa = σt − σs′: scattering is only redistributed (Eq. 3)
};

/// How material parameters map to the per-step factors and the exitant radiance.
enum class SslpvMode {
    Paper,       ///< §3.2.1 + Eq. 3 with `attenuation`; L_o = T·L_i/η² (Eq. 4 + refraction)
    Calibrated,  ///< fitted per-step absorption (SslpvCalibration); L_o = G·T·L_i/η²
    /// Not propagation: the diffusion approximation solved on the same grid (GridDiffusion),
    /// sourced by each refracted beam's first scattering along its path; the accumulation grid
    /// holds the L_i that gives the boundary's exitance with a Fresnel-weighted diffuse exit.
    /// maxSteps bounds the conjugate-gradient iterations, stopEpsilon the unbalanced power
    /// (docs/methods/sslpv.md, "Diffusion mode").
    Diffusion,
};

/// Constants of the calibrated mode (docs/methods/sslpv.md, "Calibrated mode"). Per step and
/// cell: absorption exp(−β), β = linear·σa·Δx + transport·σ_tr·Δx + diffusion·(σ_tr·Δx)²
/// + perStep·σa/σt + perStepTransport·σ_tr/σt, σ_tr = √(3σa·σt) (σt, σa reduced, mm⁻¹; Jensen et
/// al. 2001, Eq. 5), and the scattering fraction s′ = 1 − exp(−σs′·Δx) of Eq. 3; exitant radiance
/// scaled by gain[order − 1]/η². Defaults: the least-squares fit against the classical dipole's
/// thick-slab reflectance printed by `lucent-cli bench sslpv-fit`
/// (tests/unit/sslpv/test_calibrated.cpp checks the residuals).
struct SslpvCalibration {
    float linear = 0.f;            ///< weight of σa·Δx in β, ≥ 0
    float transport = 0.f;         ///< weight of σ_tr·Δx in β, ≥ 0
    float diffusion = 0.f;         ///< weight of (σ_tr·Δx)² in β, ≥ 0
    float perStep = 0.f;           ///< weight of σa/σt = 1 − α′ in β, ≥ 0
    float perStepTransport = 0.f;  ///< weight of σ_tr/σt = √(3(1 − α′)) in β, ≥ 0
    float gain[2] = {1.f, 1.f};    ///< radiance normalisation G for SH order 1 and 2, > 0
};

/// The fitted calibration (values from `lucent-cli bench sslpv-fit`, docs/methods/sslpv.md).
SslpvCalibration defaultSslpvCalibration();

/// Solver settings. Changing order/steps/skip/sinks/attenuation/mode re-propagates.
struct SslpvOptions {
    int order = 1;                ///< SH order: 1 (4 coefficients, the paper) or 2 (9)
    int maxSteps = 32;            ///< propagation steps, [0, 4096]
    int skipAccumulateSteps = 2;  ///< first steps not accumulated (§4, last paragraph)
    bool removeExitant = true;    ///< cells outside the object are sinks (paper: false, Fig. 8)
    SslpvAttenuation attenuation = SslpvAttenuation::Extinction;
    /// Stop once the flux left in the propagation grid is below stopEpsilon · injected flux
    /// (all channels); 0 runs maxSteps. [0, 1].
    float stopEpsilon = 0.f;
    /// Per-brick stop (modes Paper and Calibrated): after a step, a brick whose cells all hold
    /// less than brickStopEpsilon · c̄ in every coefficient and channel, c̄ the injected band-0
    /// coefficient per cell that can hold light (insideFraction > 0; the brightest channel's),
    /// is set to zero and counts as
    /// dark, so light that has died out in one part of the object stops being propagated there
    /// while the rest carries on; the solve ends early once every brick is dark. Unlike
    /// stopEpsilon this is local: paint that absorbs in one place does not end the propagation
    /// elsewhere. The light set to zero is SslpvStats::dropped (at most brickStopEpsilon · 2√π
    /// · c̄ per cell and step). 0: off (every brick with any non-zero value propagates: the
    /// exact solve of maxSteps steps). [0, 1].
    float brickStopEpsilon = 0.f;
    /// Active-brick propagation: each step computes only the bricks (SSLPV_BRICK_X × _Y × _Z
    /// cells) of which the brick itself or a face neighbour held non-zero flux after the
    /// previous step; every other cell's new value is exactly zero (the stencil reaches only
    /// face neighbours), so the result equals the dense solve. Light only exists inside the
    /// object and its one-cell sink shell, so this also skips everything else.
    /// Off: every cell of the box around the object is computed each step (the paper's dense
    /// GPU work). (The name predates the bricks: they replaced whole-slice skipping.)
    bool skipEmptySlices = true;
    /// Paper (default; `attenuation` applies) or Calibrated (`calibration` applies, the
    /// attenuation setting is ignored).
    SslpvMode mode = SslpvMode::Paper;
    SslpvCalibration calibration = defaultSslpvCalibration();
    /// Mode Diffusion: scale each boundary cell's exitance by the exact half-space's total over
    /// the diffusion model's at the cell's albedo (ExactReflectanceRatio); false: the model's.
    bool diffusionExactTotal = true;
    /// Mode Diffusion, with diffusionExactTotal: normalise each boundary cell's exitance to the
    /// exact slab as thick as the part it lies on (ExactSlabRatio at τ = σt′ × the cell's chord
    /// along its normal, GridDiffusion::chordLength) instead of the half-space: the model sends
    /// too much out of a layer under about 1.5 mean free paths (docs/methods/sslpv.md, "Thin
    /// parts normalised to the exact slab"). The sslpv method turns it on (parameter
    /// `diffusion-slab`); combined's diffusion part leaves it off (not measured there yet).
    bool diffusionSlabTotal = false;
    /// Mode Diffusion: send each surface point's light out with the exact half-space's
    /// distribution over exit angles at its albedo (dipole::DirpoleExitTable, as the directional
    /// dipole does); false: a Fresnel-weighted diffuse exit. Read-out only: no re-solve.
    bool diffusionExitTable = true;
    /// Mode Diffusion: the light leaving a surface point also follows the flux along the surface
    /// there, P1's radiance (φ + 3J·ω)/4π with J's tangential part (GridDiffusion::surfaceFlux):
    /// light that has travelled along the surface leaves brighter along its way (back-lit rims);
    /// false: the exitance only. Read-out only: no re-solve.
    bool diffusionSurfaceFlux = true;
    /// Mode Diffusion: the light a beam scatters first in the cell where it enters the medium is
    /// placed at its mean depth under the surface (GridDiffusion::solve's entry sources): where
    /// a cell spans several mean free paths that light is not pushed half a cell deep; false:
    /// at the cell's centre, as every other deposit. Combined turns it off (its near field is
    /// the dipole's; docs/methods/combined.md).
    bool diffusionEntryDepth = true;
    /// After a material change that keeps the shape, inject again only the beams through the
    /// changed cells (the same injection to float rounding; a full injection every 64 updates);
    /// false: every beam on every change. Mode Diffusion walks each beam's first scatterings;
    /// modes Paper and Calibrated weigh each beam by its chord's interacting fraction (σt along
    /// it), so a stroke of σt on a thin part changes how much light enters.
    bool incrementalInjection = true;
};

/// One injection texel of a reflective shadow map (§3.1).
struct SslpvInjectionSample {
    Point3f position{0.f};               ///< x_p on the surface, mm
    Normal3f normal{0.f, 0.f, 1.f};      ///< n_p, outward unit normal
    Vector3f direction{0.f, 0.f, -1.f};  ///< unit direction the light travels (light → x_p)
    Rgb flux{0.f};                       ///< Φ_p = I·Δω_p through the texel, W
};

/// Brick of the active-brick propagation (SslpvOptions::skipEmptySlices), cells per axis: one
/// z-slice thick because the light front advances one cell per step (a thicker brick would
/// recompute up to BRICK_Z − 1 dark slices ahead of it), 4 × 4 in x and y.
constexpr int SSLPV_BRICK_X = 4;
constexpr int SSLPV_BRICK_Y = 4;
constexpr int SSLPV_BRICK_Z = 1;

/// Results and energy bookkeeping of the last solve. Fluxes in W per channel.
struct SslpvStats {
    int stepsUsed = 0;
    /// Flux put into the grid: after Fresnel transmission, times the fraction of each refracted
    /// beam that interacts inside the object (1 − exp(−τ), τ its chord's optical depth)
    Rgb injected{0.f};
    Rgb remaining{0.f};  ///< flux still in the propagation grid
    Rgb exitant{0.f};    ///< flux that reached sink cells (removeExitant)
    Rgb absorbed{0.f};   ///< flux removed by the Beer attenuation
    Rgb dropped{0.f};    ///< flux set to zero in dark bricks (SslpvOptions::brickStopEpsilon)
    int injectedTexels = 0;
    int skippedTexels = 0;  ///< back-facing, zero flux, or no inside cell near x_p
    /// Beams injected again by the last solve's incremental re-injection (a stroke; 0 after a
    /// full injection or when nothing along the beams changed).
    int rewalkedTexels = 0;
    double injectMs = 0.0;
    double propagateMs = 0.0;   ///< whole propagation, including set-up and bookkeeping
    double stepsMs = 0.0;       ///< the propagation steps alone
    bool reinjected = false;    ///< this solve re-ran injection
    bool repropagated = false;  ///< this solve re-ran propagation
    /// Bricks (SSLPV_BRICK_X × _Y × _Z cells) overlapping the propagation box (the object's
    /// bounding box dilated by its sink shell, or the whole grid without sinks).
    int brickCount = 0;
    /// Bricks computed at each step (size stepsUsed); brickCount each step when dense.
    std::vector<int> activeBricksPerStep;
    /// Cells computed over all steps (active bricks' cells, plus the cells SIMD rows padded
    /// them with, which are exactly zero).
    int64_t cellsComputed = 0;
    /// Grid rows (N cells along x) whose per-cell factors the last solve refolded: N² after a
    /// new material or options, the rows of the cells markMaterialCellsDirty named, 0 for a
    /// homogeneous material (one set of factors) or an unchanged one.
    int64_t refoldedRows = 0;
};

/// Incremental SSLPV solver (see file comment). Not thread-safe; solve() uses parallelFor.
class SslpvSolver {
public:
    explicit SslpvSolver(const SslpvOptions& options = {});

    //! @{ \name Inputs (each marks what must be redone)
    /// @throw ValueError for an option out of range.
    void setOptions(const SslpvOptions& options);
    [[nodiscard]] const SslpvOptions& options() const { return m_opt; }
    /// Copies the coarse material (its GridSpec defines the LPV grid) and the relative index
    /// of refraction. Re-injects when the grid changed, always re-propagates.
    /// @throw ValueError naming the field for missing/inconsistent arrays or eta ∉ [1, 3].
    void setMaterial(const CoarseMaterial& material, float eta);
    /// The same, taking the material over (a stroke at grid 64 saves copying its ten 64³ arrays).
    void setMaterial(CoarseMaterial&& material, float eta);
    [[nodiscard]] bool hasMaterial() const { return m_hasMaterial; }
    /// The material arrays were edited in place through material(): re-propagate.
    void markMaterialDirty() {
        m_materialDirty = m_factorsDirty = true;
        m_refoldAll = true;
    }
    /// Only the listed cells' σt, σs′ and g were edited in place through material() (a stroke;
    /// not their insideFraction, which changes the shape: markMaterialDirty or setMaterial):
    /// re-propagate, refolding the per-cell factors of their rows only (bit-identical to a full
    /// refold). The cells' values are checked as setMaterial checks them.
    /// @throw ValueError for a cell index out of range or a value setMaterial would reject.
    void markMaterialCellsDirty(const std::vector<int>& cells);
    CoarseMaterial& material() { return m_material; }
    /// Replaces the injection texels (lights or mesh moved): re-inject and re-propagate.
    void setInjectionSamples(std::vector<SslpvInjectionSample> samples);
    /// The injection texels last set (SslpvSubsurfaceProvider reuses SslpvRenderer's RSM).
    [[nodiscard]] const std::vector<SslpvInjectionSample>& injectionSamples() const {
        return m_samples;
    }
    //! @}

    /// True when solve() has work to do.
    [[nodiscard]] bool isDirty() const { return m_injectionDirty || m_materialDirty; }
    /// Runs what is dirty: injection (§3.1) then propagation (§3.2).
    /// @throw ValueError if no material was set.
    const SslpvStats& solve();
    /// True when the last propagation (modes Paper and Calibrated) stopped at maxSteps with
    /// light still in flight (neither the stop rule nor the per-brick stop ended it) and no
    /// input has changed since: continuePropagation() can carry it on.
    [[nodiscard]] bool propagationInFlight() const;
    /// Carries the last propagation on by at most `steps` more steps: the steps, to the bit, that
    /// a solve with maxSteps larger by `steps` would have run after it, with the same stop rules
    /// (stopEpsilon, brickStopEpsilon). stats() then describes the whole propagation (stepsUsed
    /// in all; propagateMs and stepsMs of this call). The live preview carries a stroke's
    /// propagation on over idle frames this way (docs/methods/sslpv.md, "Convergence").
    /// @throw ValueError when !propagationInFlight() or steps < 1.
    const SslpvStats& continuePropagation(int steps);
    [[nodiscard]] const SslpvStats& stats() const { return m_stats; }

    //! @{ \name Results
    [[nodiscard]] const GridSpec& spec() const { return m_material.spec; }
    [[nodiscard]] const SslpvGrid& injection() const { return m_injection; }
    [[nodiscard]] const SslpvGrid& accumulation() const { return m_accum; }
    [[nodiscard]] const SslpvGrid& exitant() const { return m_exitant; }
    [[nodiscard]] const SslpvGrid& propagation() const { return m_prop[m_cur]; }
    /// Cell c is part of the object (insideFraction ≥ ½).
    [[nodiscard]] bool isInside(const Coord& c) const;
    /// Cell c is one radiance() (and the GL read-out) interpolates: an inside cell; in mode
    /// Diffusion only those with a boundary face (GridDiffusion::isBoundary).
    [[nodiscard]] bool isReadable(const Coord& c) const;
    /// The read-out's per-cell value (texture 0's alpha, shared/SslpvShared.h): 1 where
    /// isReadable, else the cell's inside fraction capped at ½ (0 outside the grid).
    [[nodiscard]] float readoutAlpha(const Coord& c) const;
    /// Changes whenever isReadable() may answer differently: new options, grid or inside
    /// cells (a stroke that only changes σ keeps it), so a caller can keep a copy of the flags.
    [[nodiscard]] uint64_t readableVersion() const { return m_readableVersion; }
    /// Incident radiance estimate just inside the surface at p with outward unit normal n
    /// (Eq. 5–7: area light of cross-section A = Δx², L_i = Φ_hemisphere/(Aπ)), W/(mm²·sr),
    /// from the accumulation grid sampled half a cell inside along −n (trilinear over inside
    /// cells only: isReadable). Not multiplied by Fresnel T (the caller knows ω_o).
    [[nodiscard]] Rgb radiance(const Point3f& p, const Normal3f& n) const;
    /// Radiance leaving the surface at p (outward unit normal n) towards the unit direction wo
    /// at cosine cosOut = n·wo (the caller's value: its rounding stays the caller's), W/(mm²·sr):
    /// exitScale()·T(cosOut)·radiance(p, n), T = 1 − F_r(cosOut, η) (0 for cosOut ≤ 0). In mode
    /// Diffusion, with diffusionExitTable, times the exact half-space's exit-angle correction
    /// c(α′, cosOut) per channel, α′ read with the same weights as the radiance; with
    /// diffusionSurfaceFlux, times P1's flux term max(0, 1 + 3 J_t·ω_t/(J(2A + 3μ))) (ω the
    /// refracted inside direction, ω_t its tangential part, μ its cosine; J_t read with the same
    /// weights). The GL sample pass (shaders/sslpv_sample.comp) computes the same.
    [[nodiscard]] Rgb exitantRadiance(const Point3f& p, const Normal3f& n, float cosOut,
                                      const Vector3f& wo) const;
    /// Mode Diffusion: the reduced albedo α′ per channel of the cells exitantRadiance() reads
    /// at p (the same cells and weights, so the albedo its exit-angle table is looked up at).
    /// 0 in the other modes, where no cell is readable there, or before a solve.
    [[nodiscard]] Rgb readoutAlbedo(const Point3f& p, const Normal3f& n) const;
    /// The exit-angle table exitantRadiance() applies (the process's table for η), or null when
    /// it applies none (not mode Diffusion, diffusionExitTable off, or before a solve).
    [[nodiscard]] const std::shared_ptr<const dipole::DirpoleExitTable>& exitTable() const {
        return m_exitTable;
    }
    /// True when exitantRadiance applies the surface flux's P1 term (mode Diffusion with
    /// diffusionSurfaceFlux, after a solve); the GL sample pass applies it then too.
    [[nodiscard]] bool surfaceFluxReadout() const {
        return m_opt.mode == SslpvMode::Diffusion && m_surfaceFluxReadout;
    }
    /// The diffusion solve of mode Diffusion (its stats: iterations, energy balance).
    [[nodiscard]] const GridDiffusion& diffusion() const { return m_diffusion; }
    /// Factor from radiance() times Fresnel T(ω_o) to the exitant radiance: 1/η² in Paper mode
    /// (Eq. 4 with the radiance scaling at refraction the paper leaves out, docs/reference.md),
    /// gain[order − 1]/η² in Calibrated mode. L_o = exitScale()·T(ω_o)·radiance(p, n).
    [[nodiscard]] float exitScale() const;
    //! @}

    //! @{ \name Folded propagation data (valid after solve(); for the GL path)
    /// Per-source-cell factor a·((1 − s′) + s′g^l) of channel `channel`, band `band`, as one
    /// padded plane (SslpvGrid layout), homogeneous values expanded.
    [[nodiscard]] std::vector<float> foldedFactorPlane(int channel, int band) const;
    /// 1 for inside cells, 0 for sinks, as one padded plane (all 1 when sinks are off).
    [[nodiscard]] std::vector<float> sinkMaskPlane() const;
    //! @}

private:
    void validateMaterial(const CoarseMaterial& m) const;
    void rebuildFactors();
    void inject();
    /// Fraction 1 − exp(−τ) of a refracted beam entering at `entry` (mm) along unit `wt` that
    /// interacts before it leaves the object, τ the optical depth of its chord through the
    /// medium (σt′ of the cells crossed, per channel). Light that crosses without interacting
    /// is not subsurface light: it leaves as a refracted beam, which SSLPV does not render.
    /// `chord` (optional): the part of the beam the sum walked, in grid units (cell index + ½
    /// at a centre), for the incremental re-injection's box test. `sigmaT` (optional): σt′ of
    /// another material on the same inside cells (the one an earlier injection used).
    struct BeamSegment {
        Vector3f from{0.f}, to{0.f};
    };
    [[nodiscard]] Rgb interactingFraction(const Point3f& entry, const Vector3f& wt,
                                          const Coord& injectionCell, BeamSegment* chord = nullptr,
                                          const CoarseMaterial* sigmaT = nullptr) const;
    /// Modes Paper and Calibrated, after a material change that keeps the inside cells: injects
    /// again only the beams whose chord meets the cells whose σt changed (their interacting
    /// fraction), replacing each one's deposit. False when a full injection is due instead (as
    /// reinjectChangedDiffusionSources).
    bool reinjectChangedChords();
    void propagate();
    /// The propagation steps' constants (term lists, per-cell factor pointers, the per-brick
    /// stop's threshold), rebuilt from the solver's state for each run of steps
    /// (SslpvSolver.cpp).
    struct StepKernel;
    void prepareStepKernel(StepKernel& kernel) const;
    /// Steps the propagation until `stepLimit` steps in all, the stop rule or every brick dark,
    /// from where m_run left it; then writes the stats.
    void runSteps(StepKernel& kernel, int stepLimit);
    /// Where the last propagation stands (fluxes in W per channel), so that
    /// continuePropagation() can carry it on exactly as one longer run.
    struct PropagationRun {
        Rgb injected{0.f}, remaining{0.f}, exitant{0.f}, absorbed{0.f}, dropped{0.f};
        int steps = 0;
        bool accWritten = false;   ///< a step has written the accumulation grid
        bool exitWritten = false;  ///< a step has written the exitant grid
        bool anyLit = true;        ///< some brick holds light (above the per-brick stop)
        bool inFlight = false;     ///< stopped by the step limit with light still propagating
    };
    PropagationRun m_run;
    /// Mode Diffusion's injection: each texel's refracted beam T·Φ_p is followed through the
    /// medium (half-cell midpoint steps, as interactingFraction) and the power of its first
    /// scattering, α′·(e^−τ(s) − e^−τ(s+ds))·T·Φ_p, is deposited in the cell where it happens:
    /// the collimated source of the diffusion equation with reduced coefficients.
    void injectDiffusionSources();
    /// After a material change that keeps the inside cells: walks again only the beams whose
    /// segment meets the cells whose σt′ or σs′ changed, taking their old deposits away and
    /// adding the new ones. False when a full walk is due instead (other inside cells, more
    /// than an eighth of the cells changed, or 64 incremental updates since the last full walk,
    /// which bounds the float drift).
    bool reinjectChangedDiffusionSources();
    /// Mode Diffusion's "propagation": the GridDiffusion solve and the accumulation grid it
    /// writes for radiance() and the GL read-out.
    void diffuse();

    SslpvOptions m_opt;
    CoarseMaterial m_material;
    float m_eta = 1.3f;
    std::vector<SslpvInjectionSample> m_samples;
    bool m_injectionDirty = true;
    bool m_materialDirty = true;    ///< propagation must rerun
    bool m_factorsDirty = true;     ///< per-cell factors must be refolded (material/options)
    bool m_refoldAll = true;        ///< m_factorsDirty: every row (else m_refoldRows only)
    std::vector<int> m_refoldRows;  ///< rows (z·N + y) whose cells markMaterialCellsDirty named
    bool m_hasMaterial = false;

    SslpvGrid m_injection, m_accum, m_exitant;
    SslpvGrid m_prop[2];
    int m_cur = 0;
    // Per-cell factors folded once per material change (padded layout like SslpvGrid planes):
    // m_factor[ch][band] = a · ((1 − s′) + s′·g^l), a = Beer attenuation, s′ = per-step
    // scattering fraction; m_mask = 1 inside, 0 in sink cells.
    std::vector<float> m_factor[3][3];
    std::vector<float> m_mask;
    bool m_homogeneous = false;
    float m_homFactor[3][3] = {};
    float m_homAbsorb[3] = {};
    CoordBox m_active;  ///< cells that can hold light (inside cells dilated by one, or all)
    CoordBox m_lastActive;
    int64_t m_lightCells = 0;  ///< cells that can hold light (insideFraction > 0)
    uint64_t m_readableVersion = 0;
    // Per-brick flags (index (z·bricksY + by)·bricksX + bx with SSLPV_BRICK_Z = 1):
    std::vector<uint8_t> m_injBrickLit;   ///< bricks holding injected light
    std::vector<uint8_t> m_brickLit[2];   ///< m_prop[k]'s brick may hold non-zero values
    std::vector<uint8_t> m_accBrickLit;   ///< m_accum's brick may hold non-zero values
    std::vector<uint8_t> m_exitBrickLit;  ///< m_exitant's brick may hold non-zero values
    SslpvStats m_stats;
    GridDiffusion m_diffusion;                                    ///< mode Diffusion's solver
    std::shared_ptr<const ExactSlabRatio> m_slabRatio;            ///< the process's table for η
    std::shared_ptr<const ExactReflectanceRatio> m_exactRatio;    ///< the process's table for η
    std::shared_ptr<const dipole::DirpoleExitTable> m_exitTable;  ///< see exitTable()
    /// Mode Diffusion: the accumulation grid holds the surface flux (slots
    /// LUCENT_SSLPV_DIFFUSION_FLUX_COEFF..+2) and exitantRadiance applies its P1 term.
    bool m_surfaceFluxReadout = false;
    /// The read-out's trilinear interpolation of the accumulation grid's coefficients at
    /// p − depth·Δx·n (radiance()); false where no readable cell is near.
    bool interpolateCoefficients(const Point3f& p, const Normal3f& n,
                                 float (&c)[3][SSLPV_MAX_COEFFS]) const;
    /// interpolateCoefficients' read of a part thinner than half a cell, which has no inside
    /// cell of its own: the nearest readable cells' coefficients scaled by the part's
    /// thickness (see the definition); false where no readable cell is within
    /// LUCENT_SSLPV_THIN_PART_REACH cells.
    bool thinPartCoefficients(const Point3f& p, const Normal3f& n,
                              float (&c)[3][SSLPV_MAX_COEFFS]) const;
    /// Eq. 7's L_i from interpolated coefficients (radiance()).
    [[nodiscard]] Rgb radianceFromCoefficients(const float (&c)[3][SSLPV_MAX_COEFFS],
                                               const Normal3f& n) const;
    GridDiffusionSource m_diffusionSource;  ///< mode Diffusion's first-scattering source
    /// Mode Diffusion's incremental re-injection: the material the sources were walked through,
    /// each texel's walked segment (grid units) and whether it met the medium, the sources'
    /// power bookkeeping (W, double) and the incremental updates since the last full walk.
    CoarseMaterial m_sourceMaterial;
    std::vector<BeamSegment> m_beamSegments;
    std::vector<uint8_t> m_beamEntered;
    std::array<double, 3> m_sourceInjected{}, m_sourceFirstAbsorbed{};
    int m_incrementalInjections = 0;
    /// Modes Paper and Calibrated: each texel's injection cell (spec index, UINT32_MAX when
    /// skipped) and interacting fraction; its chord is m_beamSegments[j], computed with
    /// m_sourceMaterial. (The fraction is kept, not the deposit T·(1 − e^−τ)·Φ_p/π: keeping the
    /// deposit changed how the compiler associates inject()'s products under
    /// -fassociative-math, which moved SSLPV's images in the last bits.)
    std::vector<uint32_t> m_injectionCell;
    std::vector<Rgb> m_injectionFraction;
};

}  // namespace lucent::sslpv
