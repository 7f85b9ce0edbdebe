// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Diffusion BSSRDF profiles: Jensen et al. 2001 dipole (as tabulated in Mertens et al.
/// 2005, Mertens et al. 2005, Table 1), d'Eon 2012 "A better dipole", and the Frisvad et al. 2014
/// directional dipole (ACM TOG 34(1), article 5). Each radial profile has its total diffuse
/// reflectance in closed form and by numerical quadrature. Units: σ in mm⁻¹, r in mm,
/// R_d(r) in mm⁻² (exitance per unit incident flux per unit area).
///
///     DipoleProfile p = DipoleProfile::jensen(/*sigma_a=*/0.0021, /*sigma_s=*/2.19, /*eta=*/1.3);
///     double rho = p.totalReflectance();          // closed form
///     double rhoNum = integrateProfile(p);          // quadrature, agrees to ~1e-8
///     double rd = p.Rd(/*r=*/1.0);                  // mm⁻²
///
/// Scalar (one wavelength / RGB channel) maths in double precision; Rgb helpers at the end.

#include <lucent/core/Types.h>

#include <memory>
#include <string>
#include <vector>

namespace lucent::dipole {

//! @{ \name Fresnel helpers
/// (The reflectance itself is lucent::fresnelDielectric, lucent/core/Fresnel.h.)

/// Jensen et al. 2001 diffuse Fresnel reflectance fit (Mertens et al. 2005, Table 1):
/// F_dr = −1.440/η² + 0.710/η + 0.668 + 0.0636 η, η = n_medium / n_outside.
double fresnelDiffuseReflectanceJensen(double eta);

/// Fresnel moment C_n(η) = ∫₀¹ F_r(μ) μⁿ dμ for light inside a medium of relative index
/// η = n_medium/n_outside hitting its boundary (d'Eon 2012, Sec. 2; Frisvad et al. 2014 Eq. 4).
/// 2·C₁(η) is the diffuse (hemispherical) internal reflectance. Computed by Gauss–Legendre
/// quadrature of the exact Fresnel equations (no polynomial fit), split at the critical angle.
/// For η < 1 it gives the moments of external reflection, C_n(1/η) in the papers' notation.
/// @param n 0, 1 or 2. @param eta in (0, ∞).
double fresnelMoment(int n, double eta);
//! @}

/// Which diffusion profile.
/// What every use of the published (not energy-normalised) directional dipole says: the model
/// is as published, but it is not energy-conserving (docs/methods/dipole.md §1 and §4).
inline constexpr const char* PUBLISHED_DIRPOLE_WARNING =
    "warning: the published Frisvad et al. 2014 directional dipole overestimates total "
    "reflectance (1.34 at sigma_a = 0) and is +48..131% against the reference path tracer "
    "(docs/methods/dipole.md, sections 1 and 4)";

enum class Model {
    Dipole,        ///< Jensen et al. 2001 (Mertens et al. 2005 Table 1)
    BetterDipole,  ///< d'Eon 2012
    Directional,   ///< Frisvad et al. 2014 (radial use: normal incidence)
};
/// "dipole", "better-dipole", "dirpole". @throw ValueError naming the accepted values.
Model parseModel(const std::string& name);
const char* modelName(Model m);

/// Validated per-channel optical parameters of a homogeneous medium (reduced form).
struct ScalarMedium {
    double sigma_a = 0.0;  ///< absorption σa, mm⁻¹, ≥ 0
    double sigma_s = 0.0;  ///< reduced scattering σs′, mm⁻¹, ≥ 0
    double eta = 1.3;      ///< relative index n_medium / n_outside, [1, 3]
};

/// Boundary terms that depend on η only, computed once per object (they cost 2×64 Fresnel
/// evaluations): Jensen's F_dr and the moments C₁(η), C₂(η).
struct Boundary {
    double eta = 1.0;
    double fdr = 0.0;  ///< fresnelDiffuseReflectanceJensen(η)
    double c1 = 0.0;   ///< fresnelMoment(1, η)
    double c2 = 0.0;   ///< fresnelMoment(2, η)
    /// @throw ValueError if η ∉ [1, 3].
    static Boundary of(double eta);
};

/// Radially symmetric dipole profile R_d(r) (standard or better dipole). Both are written as
///     R_d(r) = C_φ · φ(r) + C_E · E(r),
///     φ(r) = α′/(4πD) [e^{−σ_tr d_r}/d_r − e^{−σ_tr d_v}/d_v],
///     E(r) = α′/(4π) [z_r(1 + σ_tr d_r) e^{−σ_tr d_r}/d_r³ + z_v(1 + σ_tr d_v) e^{−σ_tr
///     d_v}/d_v³],
/// d_r = √(r² + z_r²), d_v = √(r² + z_v²), z_v > 0 the height of the virtual source above the
/// surface. Jensen's dipole is C_φ = 0, C_E = 1 (Mertens et al. 2005 Table 1). Medium with σt′ = 0
/// or σs′ = 0 gives the zero profile (documented clamp: no scattering, no diffuse reflectance).
class DipoleProfile {
public:
    DipoleProfile() = default;
    /// Jensen 2001 dipole, exactly Mertens et al. 2005 Table 1: σt′ = σa + σs′, α′ = σs′/σt′,
    /// D = 1/(3σt′), σ_tr = √(3σaσt′), z_r = 1/σt′, z_v = z_r + 4AD, A = (1+F_dr)/(1−F_dr).
    /// @throw ValueError for negative/NaN/Inf coefficients (> 1e6 mm⁻¹) or η outside [1, 3].
    static DipoleProfile jensen(double sigma_a, double sigma_s, double eta);
    /// d'Eon 2012 "A better dipole": D = (2σa + σs′)/(3σt′²), σ_tr = √(σa/D), z_r = 1/σt′,
    /// A = (1 + 3C₂)/(1 − 2C₁), z_v = z_r + 4AD, C_φ = (1 − 2C₁)/4, C_E = (1 − 3C₂)/2.
    /// @throw ValueError as jensen().
    static DipoleProfile better(double sigma_a, double sigma_s, double eta);
    static DipoleProfile make(Model m, const ScalarMedium& medium);
    /// Same as jensen()/better() with precomputed boundary terms (hot loops: per-pixel material).
    static DipoleProfile make(Model m, double sigma_a, double sigma_s, const Boundary& b);

    /// R_d(r) in mm⁻² (r in mm, r ≥ 0; negative r is treated as |r|).
    [[nodiscard]] double Rd(double r) const;
    /// ∫ R_d dA over the plane in closed form (Mertens et al. 2005 Eq. 7 / Jensen 2001):
    /// α′/2 [C_E (e^{−σ z_r} + e^{−σ z_v}) + C_φ/(Dσ) (e^{−σ z_r} − e^{−σ z_v})];
    /// the C_φ term → C_φ (z_v − z_r)/D as σ → 0.
    [[nodiscard]] double totalReflectance() const;
    /// ∫_{r > R} R_d(r) 2πr dr in closed form (the tail beyond R mm; R = 0 gives
    /// totalReflectance()): with d = √(R² + z²), ∫_R^∞ z(1+σd)e^{−σd}/d³ 2πr dr = 2π z e^{−σd}/d
    /// and ∫_R^∞ e^{−σd}/d 2πr dr = 2π e^{−σd}/σ (r dr = d dd), so
    /// α′/2 [C_E (z_r e^{−σd_r}/d_r + z_v e^{−σd_v}/d_v) + C_φ/(Dσ) (e^{−σd_r} − e^{−σd_v})].
    [[nodiscard]] double reflectanceBeyond(double R) const;

    [[nodiscard]] bool isZero() const { return m_alphaP <= 0.0 || m_zr <= 0.0; }
    [[nodiscard]] Model model() const { return m_model; }
    [[nodiscard]] double sigmaTr() const { return m_sigmaTr; }  ///< mm⁻¹
    [[nodiscard]] double zr() const { return m_zr; }            ///< mm
    [[nodiscard]] double zv() const { return m_zv; }            ///< mm
    [[nodiscard]] double D() const { return m_D; }              ///< mm
    [[nodiscard]] double A() const { return m_A; }
    [[nodiscard]] double alphaPrime() const { return m_alphaP; }
    [[nodiscard]] double cPhi() const { return m_cPhi; }
    [[nodiscard]] double cE() const { return m_cE; }

private:
    Model m_model = Model::Dipole;
    double m_alphaP = 0.0, m_sigmaTr = 0.0, m_zr = 0.0, m_zv = 0.0, m_D = 0.0, m_A = 1.0;
    double m_cPhi = 0.0, m_cE = 1.0;
};

/// Frisvad, Hachisuka & Kjeldsen 2014, "Directional Dipole Model for Subsurface Scattering",
/// ACM TOG 34(1):5. The diffusive part S_d(x_i, ω₁₂; x_o) = S′_d(x_o − x_i, ω₁₂, d_r)
/// − S′_d(x_o − x_v, ω_v, d_v), S′_d the ray-source diffusion term with
/// C_φ(η), C_E(η) and the 1/(4 C_φ(1/η)) exitance-to-radiance factor. Full BSSRDF:
/// S = T₁₂(ω_i) S_d T₂₁(ω_o) (Fresnel transmittances applied by the caller). d_e: paper Eq. 21;
/// negative values clamped to 0 (paper §6.1); the single-scattering term (paper Eq. 12) is not
/// included. Verified term by term against the authors' own reference program (Hachisuka &
/// Frisvad's dirpole.cpp): this is the published model, and the published model itself is
/// not energy-conserving (normal-incidence total 1.34 at σa = 0, η = 1; no α′ factor), hence
/// +48..131 % against the path tracer. Experimental: docs/methods/dipole.md §1 and §4.
class DirectionalDipole {
public:
    DirectionalDipole() = default;
    /// @throw ValueError as DipoleProfile::jensen().
    DirectionalDipole(double sigma_a, double sigma_s, double eta);
    /// The same with S_d multiplied by `energyScale` (e.g. dirpoleEnergyScale(α′, η) or
    /// DirpoleEnergyTable::scale(α′): the energy-normalised directional dipole).
    /// @throw ValueError as above, or for a scale that is not finite and ≥ 0.
    DirectionalDipole(double sigma_a, double sigma_s, double eta, double energyScale);

    /// S_d in mm⁻² sr⁻¹ (per unit incident flux entering at x_i, radiance leaving x_o before T₂₁).
    /// @param xi entry point (mm); @param ni unit outward normal at xi;
    /// @param w12 refracted direction of travel inside the medium (unit, w12·ni < 0);
    /// @param xo exit point (mm); @param no unit outward normal at xo.
    [[nodiscard]] double Sd(const glm::dvec3& xi, const glm::dvec3& ni, const glm::dvec3& w12,
                            const glm::dvec3& xo, const glm::dvec3& no) const;
    /// Radial reflectance profile at normal incidence on a plane, in mm⁻²: exitance per unit
    /// incident flux, R(r) = S_d · π(1 − 2C₁(1/η)) = S_d · 4π C_φ(1/η) (cosine integral of T₂₁).
    [[nodiscard]] double radial(double r) const;
    [[nodiscard]] bool isZero() const { return m_zero; }
    [[nodiscard]] double D() const { return m_D; }
    [[nodiscard]] double sigmaTr() const { return m_sigmaTr; }
    [[nodiscard]] double de() const { return m_de; }
    [[nodiscard]] double energyScale() const { return m_energyScale; }
    [[nodiscard]] double alphaPrime() const { return m_alphaP; }

private:
    [[nodiscard]] double sdPrime(const glm::dvec3& x, const glm::dvec3& w, double r,
                                 const glm::dvec3& no) const;
    bool m_zero = true;
    double m_D = 0.0, m_sigmaTr = 0.0, m_sigmaTp = 0.0, m_de = 0.0, m_A = 1.0;
    double m_cPhi = 0.0, m_cE = 0.0, m_norm = 0.0;  // m_norm = 1/(4 C_φ(1/η)) / (4π²)
    double m_cPhiInvEta = 0.0;
    double m_energyScale = 1.0;  // applied through m_norm
    double m_alphaP = 0.0;
};

/// What the energy-normalised directional dipole's normal-incidence total ∫ R dA is made equal
/// to (docs/methods/dipole.md §1, "Energy-normalised directional dipole").
enum class EnergyTarget {
    /// The exact total of an isotropically scattering half-space of albedo α′ behind the
    /// smooth boundary (transport, not diffusion: halfSpaceReflectance, lucent/dipole/
    /// HalfSpace.h). The default: the diffusion totals fall below it as α′ falls (the better
    /// dipole's is 0.96 / 0.91 / 0.90 of it at skin1's α′, η 1.3).
    ExactHalfSpace,
    /// d'Eon 2012's closed form for the better dipole (the normalisation before 2026-12-04).
    BetterDipole,
};
/// "exact" or "better-dipole". @throw ValueError naming the accepted values.
EnergyTarget parseEnergyTarget(const std::string& name);
const char* energyTargetName(EnergyTarget t);

/// Energy normalisation of the directional dipole: the factor s(α′, η) = ρ_target(α′, η) /
/// ρ_dirpole(α′, η) that makes the normal-incidence total ∫ R dA of the directional dipole equal
/// the target's (EnergyTarget). Both totals depend on α′ and η only (every length scales with
/// 1/σt′), so the factor is computed once per (α′, η) at σt′ = 1 mm⁻¹ (quadrature of the
/// dirpole, ≈ 0.5 ms; the exact half-space, ≈ 0.25 ms). Below α′ = DIRPOLE_MIN_ALPHA the totals
/// vanish (the diffusion ones as α′²) and the factor is held at its value there.
/// @param alphaPrime reduced albedo, [0, 1]; @param eta relative index, [1, 3].
/// @throw ValueError outside those ranges.
double dirpoleEnergyScale(double alphaPrime, double eta,
                          EnergyTarget target = EnergyTarget::ExactHalfSpace);
/// Smallest α′ at which dirpoleEnergyScale() is evaluated (below it the value is held).
constexpr double DIRPOLE_MIN_ALPHA = 1e-3;

/// dirpoleEnergyScale(α′, η, target) tabulated for one η: LOW_ALBEDO_NODES nodes uniform in
/// log α′ over [DIRPOLE_MIN_ALPHA, ½] (the scale falls like α′ there), the rest uniform in
/// s = √(1 − α′) over [½, 1] (the totals are smooth in s, but the exact one falls steeply from
/// 1 at α′ = 1 when η is high: ≈ 1 − 18 s at η 2.5, hence twice the nodes there); log s(α′)
/// interpolated linearly. Built once per object (≈ 150 ms); lookups O(1). Interpolation error ≤
/// 5·10⁻⁴ relative (test `DirpoleEnergy.TableMatchesExactScaleBetweenNodes`).
class DirpoleEnergyTable {
public:
    static constexpr int NODES = 193;
    static constexpr int LOW_ALBEDO_NODES = 64;
    DirpoleEnergyTable() = default;
    /// @throw ValueError for η ∉ [1, 3].
    explicit DirpoleEnergyTable(double eta, EnergyTarget target = EnergyTarget::ExactHalfSpace);
    /// The table for (η, target), built once per process and shared (thread-safe): renderers
    /// and providers are created per render offline, and the table costs ≈ 150 ms.
    static std::shared_ptr<const DirpoleEnergyTable> shared(double eta, EnergyTarget target);
    /// s(α′) for α′ ∈ [0, 1] (clamped). 1 for a default-constructed table.
    [[nodiscard]] double scale(double alphaPrime) const;
    [[nodiscard]] double eta() const { return m_eta; }
    [[nodiscard]] EnergyTarget target() const { return m_target; }

private:
    double m_eta = 1.0;
    EnergyTarget m_target = EnergyTarget::ExactHalfSpace;
    std::vector<double> m_scale;  // log s(α′) at the nodes (Profiles.cpp, tableAlpha)
};

/// The exit-angle correction of the exact target (EnergyTarget::ExactHalfSpace). Normalised, the
/// directional dipole returns the exact total, but it sends it out as a diffuse source under the
/// Fresnel boundary would: on a plane lit at normal incidence L_model(t) = T₂₁(t) ρ / (π(1 −
/// 2C₁(1/η))) along outside cosine t (Frisvad et al. 2014's exitance-to-radiance factor). The
/// exact half-space (halfSpaceExitance) leaves less along the normal and more at grazing angles
/// at low albedo (skin1's blue at η 1: 0.87 of L_model along the normal, 1.20 at t = 0.2) and is
/// limb-darkened near α′ = 1 (1.03 along the normal, 0.91 at t = 0.2, α′ = 0.998). The correction
/// c(α′, t) = L_exact(t) / L_model(t) multiplies the radiance leaving x_o towards the eye; its
/// flux-weighted mean over the hemisphere is 1 (both carry ρ_exact), so it moves light between
/// directions, not the total. Tabulated per η at ALBEDO_NODES nodes uniform in s = √(1 − α′) on [0,
/// 1] (α′ held ≥ DIRPOLE_MIN_ALPHA) and COSINE_NODES cosines t_j = j/(COSINE_NODES − 1) (t₀
/// evaluated at 10⁻³: both radiances vanish at grazing exit, their ratio does not), bilinear
/// between them. Built once per η (≈ 0.1 s). The layout is the GL table's
/// (shaders/shared/DirpoleShared.h).
class DirpoleExitTable {
public:
    static constexpr int ALBEDO_NODES = 64;
    static constexpr int COSINE_NODES = 16;
    DirpoleExitTable() = default;
    /// @throw ValueError for η ∉ [1, 3].
    explicit DirpoleExitTable(double eta);
    /// The table for η, built once per process and shared (thread-safe), as
    /// DirpoleEnergyTable::shared.
    static std::shared_ptr<const DirpoleExitTable> shared(double eta);
    /// c(α′, t) for α′ ∈ [0, 1] and outside cosine t ∈ [0, 1] (both clamped). 1 for a
    /// default-constructed table.
    [[nodiscard]] double correction(double alphaPrime, double cosOut) const;
    /// The nodes' values, row-major: [albedo node][cosine node].
    [[nodiscard]] const std::vector<float>& values() const { return m_values; }
    [[nodiscard]] double eta() const { return m_eta; }
    /// Outside cosine of cosine node j.
    [[nodiscard]] static double cosineNode(int j) {
        return j == 0 ? 1e-3 : double(j) / (COSINE_NODES - 1);
    }
    /// Albedo of albedo node i (before the DIRPOLE_MIN_ALPHA floor).
    [[nodiscard]] static double albedoNode(int i);

private:
    double m_eta = 1.0;
    std::vector<float> m_values;
};

/// The incidence correction of the exact target (EnergyTarget::ExactHalfSpace). The energy
/// scale matches the totals at normal incidence only; at oblique incidence the directional
/// dipole's total follows the exact one badly at low albedo (skin1's blue at η 1.3, refracted
/// cosine 0.64: 1.09× the exact; marble 0.97×). k(α′, μ₀) = [ρ_exact(μ₀)/ρ_exact(1)] /
/// [ρ_model(μ₀)/ρ_model(1)] multiplies each light sample by the cosine μ₀ of its refracted
/// direction, so the total is exact at every incidence on a plane. Tabulated per η at
/// ALBEDO_NODES albedos uniform in s = √(1 − α′) and COSINE_NODES cosines uniform over
/// [μ_min, 1], μ_min = max(√(1 − 1/η²), 0.05) (no refracted ray is shallower than the
/// critical angle's), bilinear between them; k(α′, 1) = 1. Built once per η (≈ 0.3 s, both
/// cores). Layout: shaders/shared/DirpoleShared.h.
class DirpoleIncidenceTable {
public:
    static constexpr int ALBEDO_NODES = 24;
    static constexpr int COSINE_NODES = 8;
    DirpoleIncidenceTable() = default;
    /// @throw ValueError for η ∉ [1, 3].
    explicit DirpoleIncidenceTable(double eta);
    /// The table for η, built once per process and shared (thread-safe).
    static std::shared_ptr<const DirpoleIncidenceTable> shared(double eta);
    /// k(α′, μ₀), both clamped to the table. 1 for a default-constructed table.
    [[nodiscard]] double correction(double alphaPrime, double mu0) const;
    [[nodiscard]] const std::vector<float>& values() const { return m_values; }
    [[nodiscard]] double eta() const { return m_eta; }
    /// Smallest tabulated refracted cosine μ_min.
    [[nodiscard]] double minCosine() const { return m_minCosine; }

private:
    double m_eta = 1.0;
    double m_minCosine = 0.05;
    std::vector<float> m_values;  // [albedo node][cosine node]
};

/// Numerical ∫₀^∞ f(r) 2πr dr of a radial profile: composite Gauss–Legendre in log r over
/// [1e-9·scale, 1e4·scale], plus the tail r > 1e4·scale by the substitution t = 1/r.
/// @param scale a length (mm) of the profile's core, e.g. z_r.
double integrateRadial(double (*f)(const void*, double), const void* ctx, double scale);
/// ∫ R_d dA of a dipole profile by quadrature (compare with totalReflectance()).
double integrateProfile(const DipoleProfile& p);
/// ∫ R dA of the directional dipole's normal-incidence radial profile by quadrature.
double integrateProfile(const DirectionalDipole& p);

/// ∫ S_d dA over a plane (sr⁻¹) for light refracted into it at cosine `mu0` to the inward
/// normal, by quadrature in log r and azimuth. Times π(1 − 2C₁(1/η)) (the cosine integral of
/// T₂₁, as in DirectionalDipole::radial) it is the model's total exitance per unit entering
/// flux at that incidence; at mu0 = 1 that is integrateProfile(d) (test
/// DirpoleIncidence.PlaneIntegralAtNormalIncidenceIsTheRadialOne). @param mu0 ∈ (0, 1].
double integrateSdOverPlane(const DirectionalDipole& d, double mu0);

/// Total diffuse reflectance of a model for one channel (closed form for the two dipoles;
/// quadrature for the directional dipole, which has none).
double totalReflectance(Model m, const ScalarMedium& medium);
/// R(r) of a model for one channel, mm⁻² (directional: normal incidence).
double radialProfile(Model m, const ScalarMedium& medium, double r);

/// Converts painted reduced parameters (σt = σa + σs′, σs′) of one channel to a ScalarMedium.
inline ScalarMedium fromReduced(float sigma_t, float sigma_s, float eta) {
    return {std::max(0.0, double(sigma_t) - double(sigma_s)), double(sigma_s), double(eta)};
}

}  // namespace lucent::dipole
