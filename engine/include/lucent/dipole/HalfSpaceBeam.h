// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The exact radial profile of a half-space under a normal pencil beam, by an analog
/// Monte Carlo random walk written for this purpose alone (it shares no code with the path
/// tracer or the adding–doubling solver, its own random numbers and Fresnel included), and the
/// comparison of any radial model against it. It measures *where* light leaves, which the
/// total (halfSpaceReflectance) cannot; the totals of the two agree within the walk's standard
/// error, and its first-scatter rings agree with the closed-form single scattering of
/// PhotonBeamProfile (tests HalfSpaceBeam.*). docs/methods/dipole.md §4b.
///
///     HalfSpaceBeamProfile exact = traceHalfSpaceBeam(0.9, 1.3, defaultBeamRings(), 1 << 20);
///     RadialComparison c = compareRadial(exact, [](double r) { return model.R(r); },
///                                        model.totalReflectance());
///
/// Units: lengths in mean free paths of the reduced medium (σt′ = 1), so the answer depends on
/// the albedo and η only; a model for σt′ ≠ 1 is compared at r / σt′ with R scaled by 1/σt′².

#include <lucent/dipole/Profiles.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace lucent::dipole {

/// Ring edges (outer radii, mean free paths, ascending): 8 per decade from 10⁻² to 10², the
/// first ring the disc inside 10⁻².
std::vector<double> defaultBeamRings();

/// What leaves the boundary, per unit flux that has entered it at the origin travelling along
/// the inward normal. Ring i covers [edge_{i−1}, edge_i) (edge_{−1} = 0).
struct HalfSpaceBeamProfile {
    double albedo = 0.0, eta = 1.0;
    int64_t photons = 0;
    std::vector<double> ringEdges;
    std::vector<double> ringFlux, ringStdError;  ///< exitant flux per ring and its standard error
    /// The part that scattered exactly once (it leaves at its first return to the boundary).
    std::vector<double> singleRingFlux, singleRingStdError;
    double beyond = 0.0;  ///< flux leaving beyond the last edge
    double total = 0.0, totalStdError = 0.0;
    /// Flux-weighted mean cosine of the exit direction outside the boundary, per ring and over
    /// all the exitant light: where the light leaves *towards* (1: along the normal; the
    /// half-space's radiance L(t) gives 2π∫L t² dt / total).
    std::vector<double> ringMeanExitCosine;
    double meanExitCosine = 0.0;
    /// Flux-weighted mean of ω_o·r̂ per ring, ω_o the exit direction outside, r̂ the outward
    /// radial direction on the surface: how much the light leaving there leans away from the
    /// beam (> 0) or back toward it. The azimuthal asymmetry a flux along the surface gives.
    std::vector<double> ringMeanExitRadial;
    /// The flux density under the surface, per ring: track-length estimates over the layer of
    /// depth surfaceLayerDepth (mfp) of the net radial (along r̂) and normal (outward) flux,
    /// each as a power per ring (the flux density times the ring's area). The normal one equals
    /// the ring's exitant flux as the layer thins (nothing enters there but the beam); their
    /// ratio is J_t/J_n, the quantity the grid diffusion's P1 exit term scales with
    /// (sslpv::GridDiffusion::surfaceFlux).
    std::vector<double> ringLayerRadialFlux, ringLayerNormalFlux;
    double surfaceLayerDepth = 0.05;
};

/// Flux-weighted mean exit cosine of the rings lying within [rMin, rMax] mfp (0 if none).
double meanExitCosineWithin(const HalfSpaceBeamProfile& p, double rMin, double rMax);

/// Over the rings lying within [rMin, rMax] mfp: the flux-weighted mean of ω_o·r̂ of the light
/// leaving (`lean`) and the flux along the surface over the flux through it under the surface,
/// J_t/J_n (`fluxRatio`, the layer estimates summed); lean / fluxRatio is the exit lean per unit
/// J_t/J_n that a read-out from J_t should give (0s if no ring lies there).
struct SurfaceLean {
    double lean = 0.0, fluxRatio = 0.0;
};
SurfaceLean surfaceLeanWithin(const HalfSpaceBeamProfile& p, double rMin, double rMax);

/// Traces `photons` paths (σt′ = 1, isotropic scattering with the given albedo, a smooth
/// boundary of relative index η = n_inside / n_outside: exact Fresnel reflection and total
/// internal reflection; weights multiplied by the albedo at each scattering, Russian roulette
/// below 10⁻²). Deterministic for a seed, whatever the thread count.
/// @throw ValueError for albedo ∉ [0, 0.9999], η ∉ [1, 3], photons ∉ [1, 10¹⁰] or ring edges
/// that are not positive, finite and ascending.
HalfSpaceBeamProfile traceHalfSpaceBeam(double albedo, double eta,
                                        const std::vector<double>& ringEdges, int64_t photons,
                                        uint64_t seed = 1);

/// A radial model against the exact profile.
struct RadialComparison {
    double totalRatio = 0.0;  ///< model total / exact total
    /// Where the light leaves, whatever its total: ½ Σ |q_i − p_i| over the rings (and beyond
    /// the last) of the model's and the exact profile's flux fractions, the share of the exitant
    /// light the model puts in the wrong ring (0: the same shape, 1: disjoint).
    double shapeError = 0.0;
    /// The same sum's expectation from the walk's noise alone, ½ Σ σ_i √(2/π) / total: what a
    /// perfect model would read.
    double shapeErrorFloor = 0.0;
    /// Radii holding 50 % and 90 % of the exitant flux, model over exact (log-interpolated
    /// between ring edges, in both).
    double r50Ratio = 0.0, r90Ratio = 0.0;
    std::vector<double> ringFlux;  ///< the model's flux per ring (for tables)
};

/// Integrates `profile` (R(r) in mfp⁻² per unit entering flux, r in mfp) over the rings of
/// `exact` and compares. `modelTotal`: the model's ∫ R dA (closed form where it has one).
/// @throw ValueError if the model's ring fluxes are not finite and ≥ 0 or its total is not > 0.
RadialComparison compareRadial(const HalfSpaceBeamProfile& exact,
                               const std::function<double(double)>& profile, double modelTotal);

/// One radial model's comparison (compareModelsWithBeam).
struct ModelAgainstBeam {
    std::string model;  ///< a name of radialProfileNames() (AnchorProfiles.h)
    RadialComparison comparison;
};

/// Every radial profile of radialProfileNames() (AnchorProfiles.h) for the medium `m` (σ in
/// mm⁻¹), compared with `exact` (traced at m's reduced albedo and η; lengths converted through
/// σt′). @throw ValueError if the medium does not scatter or does not match exact's albedo and
/// η (to 10⁻⁶).
std::vector<ModelAgainstBeam> compareModelsWithBeam(const ScalarMedium& m,
                                                    const HalfSpaceBeamProfile& exact);

}  // namespace lucent::dipole
