// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The diffusion approximation solved on the LPV grid: a cell-centred finite-volume
/// discretisation of −∇·(D ∇φ) + σa φ = Q over the object's cells, with the partial-current
/// (Robin) condition of a smooth dielectric boundary, φ = 2AD ∂φ/∂n_in (Groenhuis et al. 1983;
/// Haskell et al. 1994), solved per channel by Jacobi-preconditioned conjugate gradients. The
/// grid-diffusion idea for heterogeneous translucent material is Stam 1995 ("Multiple scattering
/// as a diffusion process") and Wang et al. 2010 ("Modeling and rendering of heterogeneous
/// translucent materials using the diffusion equation").
///
/// SSLPV's mode `diffusion` (SslpvSolver, docs/methods/sslpv.md "Diffusion mode") runs it in
/// place of the light propagation: unlike the LPV transfer it converges to one answer as the grid
/// is refined, and it reaches the steady state of thin, back-lit, high-albedo parts in a number
/// of iterations that grows with the grid's edge, not with the number of scattering events.
///
///     GridDiffusion d;
///     d.setMaterial(coarse, /*eta=*/1.3f);          // the operator; keeps φ for a warm start
///     d.solve(sources, {.maxIterations = 1024, .tolerance = 1e-3f});
///     float J = d.exitance(cell, /*channel=*/1);    // W/mm² through a boundary half a cell out
///
/// Units: positions mm, σ and σa mm⁻¹, D = 1/(3σt′) mm, sources W per cell, fluence rate φ and
/// exitance W/mm².

#include <lucent/material/Resample.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace lucent::sslpv {

/// Diffuse Fresnel reflectance F_dr(η) = 2∫₀¹ F(μ, η) μ dμ of a smooth boundary for a
/// cosine-weighted (Lambertian) field arriving on the side of index 1, η the other side's index
/// relative to it: F_dr(η) from outside the object, F_dr(1/η) from inside (2·C₁ of
/// dipole::fresnelMoment, exact Fresnel by quadrature). @param eta in (0, 10].
double diffuseFresnelReflectance(double eta);

/// The boundary constant A = (1 + F_dr,int)/(1 − F_dr,int), F_dr,int = F_dr(1/η), of the
/// partial-current condition (Groenhuis et al. 1983): the net flux out of the medium is
/// J = φ/(2A). A = 1 at η = 1. @param eta in [1, 3].
double diffusionBoundaryConstant(double eta);

/// Total diffuse reflectance of a half-space lit at normal incidence in this model (per unit
/// transmitted irradiance): the closed form of GridDiffusion's equation with the collimated
/// source, R = α′/((1 + σtr)(1 + 2Aσtr/3)), σtr = √(3(1 − α′)) in units of σt′ = 1.
/// @param albedo reduced albedo α′ ∈ [0, 1]. @param eta ∈ [1, 3].
double diffusionHalfSpaceReflectance(double albedo, double eta);

/// What this model's slab of optical thickness τ = σt′·thickness sends out of each face, per
/// unit transmitted irradiance at normal incidence: the closed form of GridDiffusion's equation
/// with the collimated source α′e^(−z) on 0 < z < τ (σt′ = 1) and the partial-current condition
/// on both faces, J = φ/(2A) out of each. The beam is not reflected at the far face (the
/// solver's beam walk does not reflect it). As τ → ∞ the reflectance is
/// diffusionHalfSpaceReflectance's. dipole::slabExitance is the exact transport to compare it
/// with (docs/methods/sslpv.md, "The model's own error on thin layers").
/// @param albedo reduced albedo α′ ∈ [0, 1]. @param eta ∈ [1, 3]. @param opticalThickness ≥ 0.
struct DiffusionSlabExitance {
    double reflectance = 0.0, transmittance = 0.0;
};
DiffusionSlabExitance diffusionSlabExitance(double albedo, double eta, double opticalThickness);

/// The exact half-space's total reflectance over this model's, R_exact(α′, η)/R_diffusion(α′, η)
/// (R_exact: adding–doubling, lucent/dipole/HalfSpace.h), tabulated once per η on 65 nodes
/// uniform in √(1 − α′) and interpolated linearly: the factor mode Diffusion scales each
/// boundary cell's exitance by, as the directional dipole's total is normalised to the exact
/// one (docs/methods/sslpv.md, "Diffusion mode"). 1 at α′ = 1 and where both vanish.
class ExactReflectanceRatio {
public:
    /// @throw ValueError for eta ∉ [1, 3].
    explicit ExactReflectanceRatio(double eta);
    [[nodiscard]] double eta() const { return m_eta; }
    /// The ratio at reduced albedo `albedo` (clamped to [0, 1]).
    [[nodiscard]] float operator()(float albedo) const;
    /// The exact half-space's total reflectance itself (dipole::halfSpaceReflectance at normal
    /// incidence, per unit entering flux) at `albedo` (clamped to [0, 1]), interpolated in
    /// u = √(1 − α′) as the ratio.
    [[nodiscard]] float exactTotal(float albedo) const;
    /// exactTotal's nodes: NODES + 1 values at u_i = i/NODES, α′ = 1 − u_i² (for the GL passes).
    [[nodiscard]] const std::vector<float>& exactTotals() const { return m_total; }
    static constexpr int NODES = 64;

private:
    double m_eta;
    std::vector<float> m_ratio;  ///< at u_i = i/NODES, α′ = 1 − u_i²
    std::vector<float> m_total;  ///< the exact total at the same nodes
};

/// The table for `eta`, built once per process and η (65 adding–doubling solves, ≈ 15–20 ms)
/// and shared: every solver and render of the same η reuses it. Thread-safe.
/// @throw ValueError for eta ∉ [1, 3].
std::shared_ptr<const ExactReflectanceRatio> exactReflectanceRatio(double eta);

/// The exact slab's diffuse exitance over this model's, both faces together:
/// (R + T)_exact(α′, η, τ)/(R + T)_diffusion(α′, η, τ) for a slab of optical thickness τ lit at
/// normal incidence (dipole::slabExitance over diffusionSlabExitance), tabulated once per η on
/// 33 nodes uniform in √(1 − α′) and 32 in log τ over [1/32, 32] and interpolated bilinearly (τ
/// clamped to that range: at 32 reduced mean free paths the slab is the half-space for α′ ≤ 0.99,
/// and both ratios are near 1 above). The factor that replaces ExactReflectanceRatio where a
/// boundary cell's part of the object is τ thick (SslpvOptions::diffusionSlabTotal): a layer under
/// about 1.5 mean free paths sends out too much in this model, on whichever side it is lit, by
/// the same factor for its reflected and transmitted light to a few per cent (docs/methods/
/// sslpv.md, "The model's own error on thin layers").
class ExactSlabRatio {
public:
    /// @throw ValueError for eta ∉ [1, 3].
    explicit ExactSlabRatio(double eta);
    [[nodiscard]] double eta() const { return m_eta; }
    /// The ratio at reduced albedo `albedo` (clamped to [0, 1]) and optical thickness
    /// `opticalThickness` (clamped to the table's range; NaN reads the thickest).
    [[nodiscard]] float operator()(float albedo, float opticalThickness) const;
    static constexpr int ALBEDO_NODES = 32, THICKNESS_NODES = 32;
    static constexpr float MIN_THICKNESS = 1.f / 32.f, MAX_THICKNESS = 32.f;

private:
    double m_eta;
    std::vector<float> m_ratio;  ///< [i][j]: α′ = 1 − (i/ALBEDO_NODES)², τ_j log-uniform
};

/// The table for `eta`, built once per process and η (1089 slab solves on the worker threads)
/// and shared. Thread-safe. @throw ValueError for eta ∉ [1, 3].
std::shared_ptr<const ExactSlabRatio> exactSlabRatio(double eta);

/// The lean of the light the read-out sends out where the surface carries a flux J_t along it
/// (SslpvSolver::exitantRadiance with the exact exit-angle table and the P1 term): the
/// flux-weighted mean of ω_o·t̂ over the exit hemisphere (t̂ the direction of J_t), per unit
/// J_t/J_n, to first order: (3/(2η)) ∫ t S(t)(1 − t²)/(2A + 3μ(t)) dt / ∫ t S(t) dt, with
/// S(t) = (1 − F(t, η))·c(α′, t) the exit radiance's shape over outside cosines t and μ the
/// refracted cosine inside. The exact pencil-beam walk measures the same quantity
/// (dipole::surfaceLeanWithin); `lucent-cli profile --against-exact` prints both.
/// @param albedo α′ ∈ [0, 1]. @param eta ∈ [1, 3].
double surfaceFluxExitLean(double albedo, double eta);

/// Stopping rule and bound of one solve.
struct GridDiffusionOptions {
    int maxIterations = 1024;  ///< conjugate-gradient iterations per channel, [0, 1000000]
    /// Stop once the unbalanced power Σ|r| (W) is below tolerance × the channel's source power
    /// Σ Q (W): the fraction of the injected light not yet accounted for. [0, 1]; 0: run
    /// maxIterations (or until the residual vanishes).
    double tolerance = 1e-3;
};

/// The source of one solve, W per cell and channel in spec layout (x fastest). `entry` and
/// `entryDepth` may be left empty (no entry parts); given, each has spec.voxelCount() values per
/// channel.
struct GridDiffusionSource {
    std::array<std::vector<float>, 3> power;  ///< every deposit, W
    /// The part of `power` deposited in the cell where its beam entered the medium, W, and that
    /// part's power-weighted depth under the surface, W·mm (Σ Q_k z_k over the beams, z_k the
    /// mean depth of beam k's first scattering in the cell). solve() places it at its depth.
    std::array<std::vector<float>, 3> entry, entryDepth;
};

/// Energy bookkeeping and cost of the last solve (per channel, W).
struct GridDiffusionStats {
    std::array<int, 3> iterations{};   ///< CG iterations used
    std::array<double, 3> residual{};  ///< final Σ|r| / Σ Q (0 when there is no source)
    std::array<double, 3> source{};    ///< Σ Q, W
    std::array<double, 3> absorbed{};  ///< Σ σa f φ Δx³ (f: the cell's inside fraction), W
    /// Σ over boundary faces of the flux out, W (the entry sources' direct exit included)
    std::array<double, 3> exitant{};
    std::array<double, 3> directExit{};  ///< of which entry sources sent out directly, W
    size_t cells = 0;                    ///< medium cells (unknowns per channel)
    bool warmStart = false;              ///< started from the previous solution
    double ms = 0.0;                     ///< the solve, wall time
};

/// The discretised operator and its solution (see file comment). The medium is the cells with
/// insideFraction ≥ ½ (SslpvSolver::isInside); every face between a medium cell and anything
/// else (another cell or the grid's edge) is a boundary face with the Robin condition applied
/// where the surface is: δ = (f_i − ½ + f_j)Δx from the medium cell's centre (f the inside
/// fractions; ½Δx, the cell face, for a full cell next to an empty one), and a partial cell's
/// absorption is scaled by its fraction. The voxel staircase has more area than the surface
/// it stands for (|n_x| + |n_y| + |n_z| times, for a plane of unit normal n), so each boundary
/// face's conductance is scaled by 1/(|n_x| + |n_y| + |n_z|), n from the gradient of the inside
/// fraction. Face diffusivities between medium cells are harmonic means (flux continuity).
class GridDiffusion {
public:
    /// Builds the operator for `material` (σt′ and σs′ per cell and channel; σa = σt′ − σs′
    /// clamped at 0, σt′ clamped below at 10⁻³ mm⁻¹) behind a boundary of relative index `eta`.
    /// The previous solution is kept as the next solve's starting point when the medium cells
    /// are the same (a stroke changes σ, not the shape).
    /// @throw ValueError for array sizes that do not match spec, non-finite values or eta ∉ [1, 3].
    void setMaterial(const CoarseMaterial& material, float eta);

    /// Solves A φ = Q per channel. Values at non-medium cells are ignored.
    ///
    /// An entry source at mean depth z̄ in a boundary cell whose centre is δ under the surface,
    /// z̄ < δ, lies on the path from the centre to the extrapolated boundary (2AD outside the
    /// surface), which the discretisation treats as one conductance. In one dimension, and
    /// exactly for a linear φ, a source there is the fraction (2AD + z̄)/(2AD + δ) of it at the
    /// centre and the rest leaving through the boundary; with absorption on the way (κ² = σa/D)
    /// the two ends get sinh(κ(z̄ + 2AD))/sinh(κ(δ + 2AD)) and sinh(κ(δ − z̄))/sinh(κ(δ + 2AD))
    /// and the rest is absorbed (that form measured better against the exact transport:
    /// docs/methods/sslpv.md, "The light that enters a cell, at its depth"). So where cells are
    /// coarser than the mean free path the light scattered first near the surface is not pushed
    /// half a cell deep, which sent too much of it through thin layers. The direct part is
    /// spread over the cell's boundary faces and read out with exitance(); stats() counts it as
    /// exitant (directExit) and what the way absorbs as absorbed. A cell with boundary faces on
    /// opposite sides (a layer one cell thick) keeps its entry sources at the centre: its one
    /// read-out value stands for both faces.
    /// @throw ValueError before setMaterial, for a wrong size or a negative/non-finite source.
    const GridDiffusionStats& solve(const GridDiffusionSource& source,
                                    const GridDiffusionOptions& options);
    /// solve() with every deposit at its cell's centre (no entry parts). @param source W per
    /// cell, spec.voxelCount() values per channel (x fastest).
    const GridDiffusionStats& solve(const std::array<std::vector<float>, 3>& source,
                                    const GridDiffusionOptions& options);

    [[nodiscard]] const GridDiffusionStats& stats() const { return m_stats; }
    [[nodiscard]] const GridSpec& spec() const { return m_spec; }
    /// The boundary constant A of the last setMaterial (diffusionBoundaryConstant(η)).
    [[nodiscard]] double boundaryConstant() const { return m_boundaryA; }
    /// True for a medium cell (linear index of spec).
    [[nodiscard]] bool isMedium(size_t cell) const {
        return cell < m_compact.size() && m_compact[cell] >= 0;
    }
    /// True for a medium cell with at least one boundary face: the cells whose exitance()
    /// stands for the surface (the read-out interpolates these only).
    [[nodiscard]] bool isBoundary(size_t cell) const {
        return cell < m_boundary.size() && m_boundary[cell] != 0;
    }
    /// Fluence rate φ of the cell (W/mm²), 0 outside the medium.
    [[nodiscard]] float fluence(size_t cell, int channel) const;
    /// Net flux J = φ D/(2AD + δ) (W/mm²) leaving through the surface δ from the cell's centre
    /// (δ: the mean over its boundary faces, ½Δx for an interior cell): the Robin condition
    /// J = φ_b/(2A) with φ_b extrapolated along the flux; plus, at a boundary cell, the entry
    /// sources' direct exit per unit of its boundary area (see solve). 0 outside the medium.
    [[nodiscard]] float exitance(size_t cell, int channel) const;
    /// The flux along the surface at a boundary cell, per channel (W/mm², vectors in the
    /// surface's tangent plane): Fick's law J_t = −D ∇_t φ_b on the boundary, where the Robin
    /// condition makes the surface fluence φ_b = 2A·J, so J_t = −2AD ∇_t J with ∇_t J the
    /// least-squares gradient of exitance() over the boundary cells of the 3×3×3 neighbourhood, in
    /// the tangent plane of the inside fraction's outward normal. It is what the read-out's P1 exit
    /// term needs (SslpvSolver::exitantRadiance; docs/methods/sslpv.md, "Light along the surface").
    /// Zero outside the boundary, where the normal is undefined (a shell thinner than the stencil)
    /// and where the neighbours do not span the plane.
    [[nodiscard]] std::array<Vector3f, 3> surfaceFlux(size_t cell) const;
    /// The length of the chord through the medium from a boundary cell's surface point inward
    /// along its normal (mm): the local thickness of the part the cell lies on — its depth δ
    /// plus the march from its centre along −n until the inside fraction, interpolated
    /// trilinearly, falls below ½ (steps of ½ cell, the crossing interpolated). Where the normal
    /// is undefined (a shell thinner than the stencil) the cell's own medium, f·Δx. Computed on
    /// the first call after a change of shape (≈ 26 ms at 64³, on the worker threads; that call
    /// must not race another), 0 outside the boundary.
    [[nodiscard]] float chordLength(size_t cell) const;

private:
    GridSpec m_spec;
    float m_eta = 1.f;
    double m_boundaryA = 1.0;
    std::vector<int32_t> m_compact;  ///< spec index → unknown index, −1 outside the medium
    std::vector<uint32_t> m_cells;   ///< unknown index → spec index
    /// Neighbour unknown per face (±x, ±y, ±z), structure of arrays; a boundary face points at
    /// the zero sentinel m_cells.size().
    std::array<std::vector<uint32_t>, 6> m_neighbour;
    /// Per channel: conductance G = Δx·D_face (mm²) of each interior face, whose flux is
    /// G (φ_i − φ_j) W, and the diagonal (every face's conductance, boundary ones included, plus
    /// σa Δx³).
    std::array<std::array<std::vector<float>, 6>, 3> m_conductance;
    std::array<std::vector<float>, 3> m_diagonal;
    std::array<std::vector<float>, 3> m_boundaryConductance;  ///< Σ boundary faces' conductance
    std::array<std::vector<float>, 3> m_sigmaA;
    std::array<std::vector<float>, 3> m_diffusivity;
    std::array<std::vector<float>, 3> m_phi;  ///< solution per unknown (+ sentinel)
    std::vector<float> m_depth;  ///< per unknown: its centre's depth under the surface, mm
    /// Per unknown: its boundary faces' area (mm², staircase-corrected as their conductance) and
    /// which faces they are (bit f for face f of ±x, ±y, ±z).
    std::vector<float> m_boundaryArea;
    std::vector<uint8_t> m_boundaryFaces;
    /// Per channel and unknown: the entry sources' direct exit of the last solve, W/mm².
    std::array<std::vector<float>, 3> m_directExitance;
    /// Per unknown: the outward unit normal (−∇ of the inside fraction), zero where that
    /// gradient vanishes; used by surfaceFlux().
    std::vector<Vector3f> m_normal;
    std::vector<float> m_fraction;  ///< per spec cell: the inside fraction (chordLength's march)
    mutable std::vector<float> m_chord;  ///< per unknown; empty until chordLength() asks
    std::vector<uint8_t> m_boundary;     ///< per spec cell: 1 for a boundary cell
    bool m_hasMaterial = false;
    bool m_phiValid = false;
    GridDiffusionStats m_stats;
};

}  // namespace lucent::sslpv
