// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The fixed maths of SSLPV (Børlum et al. 2011, Børlum et al. 2011): the per-face
/// propagation matrices of §4 computed by numerical integration, exact dielectric Fresnel
/// transmittance and Snell refraction used by injection (§3.1, Eq. 1) and rendering (§3.3, Eq.
/// 4/7), and the reflective-shadow-map texel solid angle of §3.1 with the near-plane correction of
/// the SSLPV project page errata.
///
///     const auto& mats = propagationMatrices(1);            // 6 matrices, 4×4 each
///     float m = mats[neighbourIndex(0, +1)].at(0, 3);        // ≈ −0.240 (paper, §4)

#include <lucent/core/Types.h>

#include <array>

namespace lucent::sslpv {

/// Maximum SH coefficient count supported by the solver (order 2 → 9).
inline constexpr int SSLPV_MAX_COEFFS = 9;

/// Index of the neighbour (source) cell s = d + sign·e_axis of a destination cell d:
/// 0: +x, 1: −x, 2: +y, 3: −y, 4: +z, 5: −z.
constexpr int neighbourIndex(int axis, int sign) {
    return 2 * axis + (sign > 0 ? 0 : 1);
}

/// ΣfM_{f,d←s}: maps the SH coefficients of the point light in source cell s to those of the
/// point light created in the destination cell d (§4, the matrix below Eq. 7's derivation).
struct PropagationMatrix {
    int count = 4;                                               ///< coefficients (4 or 9)
    std::array<float, SSLPV_MAX_COEFFS * SSLPV_MAX_COEFFS> m{};  ///< row-major, count×count used
    [[nodiscard]] float at(int row, int col) const { return m[row * SSLPV_MAX_COEFFS + col]; }
};

/// Computes ΣfM_{f,d←s} for the source at d + sign·e_axis in a uniform grid of unit cells:
///   [M_f]_{ij} = (1/π) ∫_{2π} (n_f·ω) y_i(ω) dω · ∫_{Δω_{f,s}} y_j(ω) dω       (§4)
/// summed over the five faces f of d other than the one shared with s. The first factor is the
/// analytic projection of the clamped-cosine lobe about the face normal n_f (zonal coefficients
/// √π/2, √(π/3), √(5π)/8, the SSLPV project page errata); the solid-angle integral over each face
/// is computed by tensor Gauss–Legendre quadrature over the face area, dω = |n_f·r| / |r|³ dA, in
/// double.
/// @param order 1 (4 coefficients, the paper) or 2 (9).
/// @param axis 0, 1, 2. @param sign +1 or −1.
/// @param nodes Gauss–Legendre nodes per face dimension (≥ 2).
/// @throw ValueError for an unsupported order/axis/sign/nodes.
PropagationMatrix computePropagationMatrix(int order, int axis, int sign, int nodes = 24);

/// The six matrices of `order`, indexed by neighbourIndex(); computed once per process (first
/// call) and cached. @throw ValueError for an order other than 1 or 2.
const std::array<PropagationMatrix, 6>& propagationMatrices(int order);

/// Snell refraction of the travel direction `wi` (unit, pointing into the surface, i.e.
/// dot(wi, n) < 0) through the interface with outward unit normal `n`, from outside (index 1)
/// into a medium of relative index `eta`. @return the unit transmitted travel direction.
Vector3f refractInto(const Vector3f& wi, const Normal3f& n, float eta);

/// Solid angle (sr) of one texel of a perspective reflective shadow map (§3.1):
///   Δω_p = A_p cos θ_p / |r_p|²,  A_p = (2·near·tan(FOV/2))²·α / (N_x N_y),  |r_p| = near/cos θ_p
/// which is the paper's 4α tan²(FOV/2) cos³θ_p / (N_x N_y) once A_p is divided by near²
/// (the SSLPV project page errata: the printed formula assumes near = 1).
/// @param tanHalfFov tan(FOV/2) of the horizontal field of view. @param aspect α = height/width.
/// @param nx, ny texels. @param cosTheta angle between the plane normal and r_p.
/// @param nearPlane distance of the virtual plane (mm); cancels out, kept to state the units.
float rsmTexelSolidAngle(float tanHalfFov, float aspect, int nx, int ny, float cosTheta,
                         float nearPlane = 1.f);

}  // namespace lucent::sslpv
