// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The painted material as a half-space model should read it: every diffusion method
/// here (the dipoles, the directional dipole, combined's local kernel) reads σt′ and σs′ at the
/// surface point and assumes the half-space below is made of that medium. A thin
/// high-scattering layer over an absorbing core then renders as if it were the layer all the
/// way down: 1.47× too bright on the evaluation suite's layer-over-core case, where averaging
/// σ over depth made it 0.18× (docs/evaluation.md). Light that reaches the core is absorbed
/// there, not in a mean medium.
///
/// The layered read-out keeps σt′ at each surface voxel and replaces its reduced albedo α′ by
/// the albedo of the homogeneous half-space that returns as much light as the column of
/// material under it. Along the inward normal the column is cut into layers of half a voxel;
/// their reflectance is stacked in the two-flux (Kubelka–Munk) model with diffusion's decay
/// constant, K = 2σa, S = (3σs′ − σa)/4, so √(K² + 2KS) = σ_tr = √(3σaσt′) (Kubelka 1954 for
/// the layer over a background; the coefficients matched to diffusion as in Star, Marijnissen
/// & van Gemert 1988). What the column returns beyond the surface medium alone, in that model
/// and behind the boundary's internal reflection, is added to the exact half-space total of the
/// surface medium (HalfSpace.h), and α′ is the albedo whose exact total is that: a homogeneous
/// column returns its own albedo exactly, and the two-flux model's own error enters only
/// through a difference. Checked against the exact layered solver
/// (layeredHalfSpaceReflectance) in test LayeredMaterial.*; measured on the suite in
/// docs/methods/dipole.md ("Layered material").
///
///     MaterialVolume seen = layeredEquivalent(volume, eta);   // σs′ rewritten at the surface
///     LayeredReadout live(volume, eta);                       // the same, updated per stroke
///
/// Units: σ in mm⁻¹, thickness in mm.

#include <lucent/material/MaterialVolume.h>

#include <vector>

namespace lucent::dipole {

/// One layer of a column, for the two-flux stack.
struct TwoFluxLayer {
    double sigmaA = 0.0;       ///< absorption, mm⁻¹
    double sigmaSp = 0.0;      ///< reduced scattering σs′, mm⁻¹
    double thicknessMm = 0.0;  ///< ignored for the last layer (semi-infinite)
};

/// The two-flux diffuse reflectance of `layers` (top first, the last semi-infinite), no
/// boundary: the stack is built from the bottom up with Kubelka's layer-over-background
/// formula. A layer without absorption is held at σa ≥ 10⁻⁹ σt′ (its K/S = 0 is a removable
/// singularity). @throw ValueError for no layers or a negative or non-finite value.
double twoFluxReflectance(const std::vector<TwoFluxLayer>& layers);

/// The reduced albedo of the homogeneous half-space (behind the boundary of index `eta`) whose
/// exact total reflectance is R_exact(α′_top) + R_b(column) − R_b(top medium as a half-space),
/// R_b the two-flux reflectance behind the boundary: the column's albedo as a half-space model
/// should read it.
/// Exactly α′_top for a homogeneous column. @throw ValueError as twoFluxReflectance, η ∉ [1, 3].
double layeredEquivalentAlbedo(const std::vector<TwoFluxLayer>& column, double eta);

/// How the columns are taken from the volume.
struct LayeredReadoutSettings {
    /// Voxels under the surface that get a layered albedo (the methods read σ within 3 voxels
    /// of the surface: IrradiancePass's materialInside and the GL passes' inset).
    int surfaceBandVoxels = 4;
    /// Deepest a column reaches, voxels. Under a medium of diffusion length ℓ the background
    /// below depth z weighs e^{−2z/ℓ}, so the column stops earlier where that is below
    /// stopWeight.
    int maxDepthVoxels = 16;
    double stopWeight = 1e-4;
};

/// The layered read-out of a volume, kept up to date brick by brick while it is painted:
/// every inside voxel within surfaceBandVoxels of the surface holds, per channel,
/// σs′ = layeredEquivalentAlbedo(column under it) · σt′; the rest is the volume's. The inward
/// direction is the gradient of the inside mask smoothed over 2·surfaceBandVoxels + 1 voxels
/// (computed once per mask); the column runs along it in half-voxel steps, runs of one medium
/// merged into one layer, until it leaves the object (the medium is then taken to continue)
/// or reaches maxDepthVoxels. A homogeneous volume is read as it is.
///
///     LayeredReadout seen(volume, eta);              // full build
///     provider.setMaterial(&seen.volume());
///     provider.uploadBricks(seen.update(volume, volume.takeDirtyBricks()));   // per stroke
class LayeredReadout {
public:
    LayeredReadout() = default;
    /// @throw ValueError for η ∉ [1, 3].
    LayeredReadout(const MaterialVolume& volume, double eta,
                   const LayeredReadoutSettings& settings = {});

    /// The read-out (the volume's grid).
    [[nodiscard]] const MaterialVolume& volume() const { return m_seen; }
    [[nodiscard]] double eta() const { return m_eta; }

    /// After the bricks `dirtyBricks` of `volume` (the one it was built from) changed: looks at
    /// the bricks a column through a dirty brick can start in (within maxDepthVoxels), recomputes
    /// there the voxels in a dirty brick or whose column samples one (the others read what they
    /// read before), and returns those bricks' indices, for the GL upload. The result is the
    /// full rebuild's, bit for bit. A volume that was homogeneous is identical to its read-out,
    /// so its first stroke is incremental too. Every brick dirty (a new inside mask) rebuilds
    /// everything. @throw ValueError for another grid or a brick out of range.
    std::vector<int> update(const MaterialVolume& volume, const std::vector<int>& dirtyBricks);

private:
    MaterialVolume m_seen;
    std::vector<float> m_smoothInside;  ///< the inside mask, box-blurred (dense, x fastest)
    double m_eta = 1.0;
    LayeredReadoutSettings m_settings;
};

/// LayeredReadout(volume, eta, settings).volume(): the read-out, once.
MaterialVolume layeredEquivalent(const MaterialVolume& volume, double eta,
                                 const LayeredReadoutSettings& settings = {});

}  // namespace lucent::dipole
