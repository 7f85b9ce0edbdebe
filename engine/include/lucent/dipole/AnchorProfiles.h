// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Two published radial profiles kept as anchors to measure the shipped models against
/// (issue 14 item 3), not used by any renderer: Christensen & Burley 2015's normalised diffusion
/// ("Approximate Reflectance Profiles for Efficient Subsurface Scattering", Pixar Technical Memo
/// 15-04) and photon beam diffusion (Habel, Christensen & Jarosz 2013, "Photon Beam Diffusion: A
/// Hybrid Monte Carlo Method for Subsurface Scattering", CGF 32(4)). Both for light entering a
/// plane at normal incidence; units as Profiles.h (σ in mm⁻¹, r in mm, R(r) in mm⁻² per unit
/// entering flux). docs/methods/dipole.md §4b measures them, with the shipped models, against
/// the exact half-space (HalfSpaceBeam.h).
///
///     BurleyProfile b = BurleyProfile::searchlight(0.032, 0.74, 1.3);   // skin1, red
///     double rd = b.R(1.0);                 // mm⁻²
///     PhotonBeamProfile p(0.032, 0.74, 1.3);
///     double total = p.totalReflectance();  // multiple (closed form) + single (quadrature)

#include <lucent/dipole/Profiles.h>

#include <functional>
#include <string>
#include <vector>

namespace lucent::dipole {

/// Christensen & Burley 2015 Eq. 5, the "searchlight" fit of the scaling factor between the
/// mean free path ℓ and the profile's shape parameter d = ℓ/s, as a function of the surface
/// albedo A (the total diffuse reflectance): s = 1.85 − A + 7|A − 0.8|³.
double burleySearchlightScale(double surfaceAlbedo);

/// Christensen & Burley 2015 normalised diffusion: R(r) = A (e^{−r/d} + e^{−r/(3d)}) / (8π d r),
/// whose integral over the plane is A exactly (∫ R 2πr dr = A (d + 3d)/(4d)).
class BurleyProfile {
public:
    BurleyProfile() = default;
    /// @param surfaceAlbedo A ∈ [0, 1]; @param d shape length in mm (> 0, finite).
    /// @throw ValueError outside those ranges.
    BurleyProfile(double surfaceAlbedo, double d);
    /// The anchor as measured here: A the exact total of the half-space (halfSpaceReflectance at
    /// α′ = σs′/σt′ and η; the paper fits A from its own Monte Carlo), ℓ = 1/σt′ (isotropic
    /// scattering in the reduced medium) and d = ℓ / burleySearchlightScale(A). A medium without
    /// scattering gives the zero profile. @throw ValueError as DipoleProfile::jensen().
    static BurleyProfile searchlight(double sigma_a, double sigma_s, double eta);

    /// R(r), mm⁻² (r ≥ 0; R(0) = +∞, an integrable 1/r singularity).
    [[nodiscard]] double R(double r) const;
    [[nodiscard]] double totalReflectance() const { return m_A; }
    /// ∫_{r > radius} R dA = A (¼ e^{−radius/d} + ¾ e^{−radius/(3d)}).
    [[nodiscard]] double reflectanceBeyond(double radius) const;
    [[nodiscard]] double d() const { return m_d; }
    [[nodiscard]] bool isZero() const { return m_A <= 0.0; }

private:
    double m_A = 0.0, m_d = 1.0;
};

/// Photon beam diffusion for a beam entering a plane at normal incidence (Habel et al. 2013
/// §4): the multiple-scattering part integrates the better dipole's point source (d'Eon 2012:
/// D = (2σa + σs′)/(3σt′²), σtr = √(σa/D), C_φ, C_E, virtual source 4AD further down) along the
/// refracted beam, with source density Q(t) = σs′ e^{−σt′ t} at depth t,
///     R_ms(r) = ∫₀^∞ Q(t) [C_φ φ(r; t) + C_E E(r; t)] dt,
/// and the single-scattering part is the exact first-scatter exitance of the isotropic reduced
/// medium behind the Fresnel boundary (the paper's R^(1), computed by quadrature here):
///     R_ss(r) = α′ σt′ / (4π r) ∫₀¹ T(μ) e^{−σt′ r (1 + 1/μ)/τ(μ)} / τ(μ) dμ,   τ = √(1 − μ²)/μ,
/// μ the cosine of the upward direction inside, T = 1 − F_r(μ, η) the transmittance out.
class PhotonBeamProfile {
public:
    PhotonBeamProfile() = default;
    /// @throw ValueError as DipoleProfile::better().
    PhotonBeamProfile(double sigma_a, double sigma_s, double eta);

    /// R_ms + R_ss, mm⁻².
    [[nodiscard]] double R(double r) const { return multiple(r) + single(r); }
    /// The beam-integrated better dipole, by composite Gauss–Legendre in log depth.
    [[nodiscard]] double multiple(double r) const;
    /// The exact single-scattering exitance (quadrature in μ).
    [[nodiscard]] double single(double r) const;
    /// ∫ R_ms dA in closed form: σs′/(σt′ + σtr) [C_E/2 (1 + e^{−4ADσtr}) + C_φ/(2Dσtr)
    /// (1 − e^{−4ADσtr})] (each point source's total, Profiles.h, integrated against Q).
    [[nodiscard]] double multipleTotal() const;
    /// ∫ R_ss dA = α′/2 ∫₀¹ T(μ) μ/(1 + μ) dμ (quadrature).
    [[nodiscard]] double singleTotal() const;
    [[nodiscard]] double totalReflectance() const { return multipleTotal() + singleTotal(); }
    [[nodiscard]] bool isZero() const { return m_sigmaS <= 0.0 || m_sigmaT <= 0.0; }

private:
    double m_sigmaS = 0.0, m_sigmaT = 0.0, m_eta = 1.0;
    double m_D = 0.0, m_sigmaTr = 0.0, m_zb2 = 0.0;  // m_zb2 = 4AD: virtual source offset
    double m_cPhi = 0.0, m_cE = 0.0;
};

/// A radial profile by name, for tools and comparisons (lucent-cli profile, HalfSpaceBeam.h).
struct NamedRadialProfile {
    std::string name;
    std::function<double(double)> R;  ///< R(r), mm⁻², r in mm; normal incidence
    double total = 0.0;               ///< ∫ R dA (closed form where the model has one)
};

/// The names makeRadialProfile accepts: "dipole", "better-dipole", "dirpole" (as published),
/// "dirpole-normalised" (scaled to the exact half-space total, the renderers' default),
/// "burley", "photon-beam" (the paper's sum) and "photon-beam-ms" (its multiple term alone).
const std::vector<std::string>& radialProfileNames();

/// @throw ValueError for an unknown name (listing the accepted ones) or a medium the model
/// refuses (as DipoleProfile::jensen()).
NamedRadialProfile makeRadialProfile(const std::string& name, const ScalarMedium& m);

}  // namespace lucent::dipole
