// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The exact total diffuse reflectance of a homogeneous, isotropically scattering
/// half-space behind a smooth dielectric boundary: plane-parallel radiative transfer solved by
/// adding–doubling (van de Hulst 1980, "Multiple Light Scattering", Vol. 1 §5; Prahl 1995,
/// "The adding–doubling method", in Welch & van Gemert, "Optical-Thermal Response of
/// Laser-Irradiated Tissue", ch. 5). No diffusion approximation: this is the transport answer a
/// diffusion profile's total should have, and it shares no code with the path tracer.
///
///     double rho = halfSpaceReflectance(/*albedo=*/0.84, /*eta=*/1.3);   // 0.213
///
/// Uses: the directional dipole's energy normalisation (DirpoleEnergyTable, Profiles.h) and the
/// tests' closed-form checks (Chandrasekhar's H-function at η = 1).

#include <vector>

namespace lucent::dipole {

/// Quadrature nodes per interval of the polar cosine (two intervals, split at the critical
/// angle, when η > 1): 8 agree with 64 to 2.7·10⁻⁵ over η 1–3, albedo 0.05–0.9999, μ₀ 0.05–1
/// (test HalfSpace.NodeCountConverges), at 0.24 ms a solve.
constexpr int HALF_SPACE_NODES = 8;

/// What a half-space sends back out for a collimated beam (halfSpaceExitance).
struct HalfSpaceExitance {
    double reflectance = 0.0;  ///< exitance per unit entering flux (dimensionless)
    /// Radiance leaving along each requested outside cosine, per unit entering flux, sr⁻¹
    /// (outside the boundary: divided by η², the n² law). 2π ∫₀¹ L(t) t dt = reflectance.
    std::vector<double> radiance;
};

/// Exitance leaving the boundary per unit flux that has entered it, for a collimated beam
/// travelling into the medium at cosine `mu0` to the inward normal (normal incidence: 1), and
/// the radiance it leaves with along the outside cosines `exitCosines` (each in (0, 1]; they
/// are carried through the solve as directions of zero quadrature weight, so their radiance is
/// exact, not interpolated). The medium scatters isotropically with single-scattering albedo
/// `albedo` (for a diffusion model, its reduced albedo α′ = σs′/σt′); its boundary is smooth
/// with relative index η = n_medium / n_outside, so light inside meets the exact Fresnel
/// reflectance, total internal reflection included. Dimensionless: the answer depends on
/// albedo, η and μ₀ only (lengths scale with 1/σt). At albedo 1 the reflectance is 1 (nothing
/// is absorbed: a random walk in depth is recurrent) and the radiance is the limit's shape
/// (solved at 1 − 10⁻¹⁰ and scaled to a total of 1).
/// @throw ValueError for albedo ∉ [0, 1], η ∉ [1, 3], μ₀ ∉ (0, 1], an exit cosine ∉ (0, 1] or
/// nodes ∉ [2, 256].
HalfSpaceExitance halfSpaceExitance(double albedo, double eta, double mu0,
                                    const std::vector<double>& exitCosines,
                                    int nodes = HALF_SPACE_NODES);

/// halfSpaceExitance(albedo, eta, mu0, {}, nodes).reflectance.
double halfSpaceReflectance(double albedo, double eta, double mu0 = 1.0,
                            int nodes = HALF_SPACE_NODES);

/// What a homogeneous slab between two smooth dielectric boundaries sends out of each face for
/// a collimated beam entering its top (slabExitance), per unit entering flux.
struct SlabExitance {
    double reflectance = 0.0;    ///< diffuse exitance out of the lit face
    double transmittance = 0.0;  ///< diffuse exitance out of the far face
    /// The unscattered beam out of the far face, and out of the lit face after reflecting off
    /// the far one (both specular: a back-lit slab's transmittance leaves this out).
    double directTransmittance = 0.0, directReflectance = 0.0;
    /// Diffuse radiance leaving each face along the requested outside cosines, per unit
    /// entering flux, sr⁻¹ (as HalfSpaceExitance::radiance).
    std::vector<double> reflectedRadiance, transmittedRadiance;
};

/// The exact answer for a slab of optical thickness `opticalThickness` (τ = σt′ · thickness),
/// albedo `albedo` and the same index η on both faces: the transport of halfSpaceExitance with
/// a second boundary, whose exact Fresnel reflection (total internal reflection included)
/// returns light from below as the first boundary does from above; the unscattered beam is
/// reflected at the faces too (its cosine μ₀ is kept). At albedo 1 the four parts sum to 1. The
/// measuring stick for the diffusion solve's thin layers (docs/methods/sslpv.md); `exitCosines`
/// as in halfSpaceExitance. @throw ValueError as halfSpaceExitance, or for a thickness that is
/// negative or not finite.
SlabExitance slabExitance(double albedo, double eta, double opticalThickness, double mu0 = 1.0,
                          const std::vector<double>& exitCosines = {},
                          int nodes = HALF_SPACE_NODES);

/// One homogeneous layer of a layered half-space: its reduced albedo α′ and its optical
/// thickness τ = σt′ · thickness (dimensionless).
struct HalfSpaceLayer {
    double albedo = 0.0;
    double opticalThickness = 0.0;  ///< ignored for the last layer (it is semi-infinite)
};

/// The exact total reflectance of a stack of homogeneous, isotropically scattering layers
/// (top first; the last one semi-infinite) behind the smooth dielectric boundary, for a
/// collimated beam at inward cosine `mu0`, per unit entering flux: the same transport as
/// halfSpaceReflectance (which a one-layer stack equals), the layers index-matched to each
/// other. The measuring stick for the layered-material read-out of the diffusion methods
/// (LayeredMaterial.h). @throw ValueError as halfSpaceExitance, for no layers or a thickness
/// that is negative or not finite.
double layeredHalfSpaceReflectance(const std::vector<HalfSpaceLayer>& layers, double eta,
                                   double mu0 = 1.0, int nodes = HALF_SPACE_NODES);

}  // namespace lucent::dipole
