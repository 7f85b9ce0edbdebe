// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Gauss–Legendre quadrature: the one rule the dipole profiles, the SSLPV transfer
/// matrices and the half-space solver share.
///
///     const QuadratureRule g = gaussLegendre(64).mappedTo(0.0, 1.0);
///     double s = 0.0;
///     for (size_t i = 0; i < g.x.size(); ++i) s += g.w[i] * f(g.x[i]);   // ∫₀¹ f

#include <vector>

namespace lucent {

/// Nodes x and weights w of a quadrature rule: ∫ f ≈ Σ w_i f(x_i).
struct QuadratureRule {
    std::vector<double> x, w;
    /// The rule moved from [−1, 1] to [a, b] (nodes mapped linearly, weights scaled by (b − a)/2).
    [[nodiscard]] QuadratureRule mappedTo(double a, double b) const;
};

/// Gauss–Legendre rule of n nodes on [−1, 1], exact for polynomials of degree 2n − 1; nodes by
/// Newton iteration on P_n (Numerical Recipes §4.6), ascending. @throw ValueError for n ∉ [1,
/// 1024].
QuadratureRule gaussLegendre(int n);

}  // namespace lucent
