// SPDX-License-Identifier: MIT
/// @file
/// @brief Adding–doubling for an isotropic half-space behind a Fresnel boundary (HalfSpace.h).
///
/// Radiance is kept at the quadrature nodes μ_i of the polar cosine (azimuth-averaged: with an
/// isotropic phase function only the azimuthal mean carries flux). A layer is its reflection and
/// transmission operators R, T on radiance vectors (the quadrature weights folded in, so that
/// layers compose by plain matrix products), plus, for the collimated beam, the diffuse radiance
/// r_c, t_c it sends up and down and its direct transmission d. A layer of optical thickness Δτ
/// (van de Hulst 1980 §5.2, first order in Δτ):
///     R_ij = a Δτ w_j / (2 μ_i),  T_ij = e^{−Δτ/μ_i} δ_ij + R_ij,
///     r_c,i = t_c,i = a Δτ / (4π μ₀ μ_i),  d = e^{−Δτ/μ₀}
/// (unit beam flux per unit area; the emission of a thin layer seen along μ_i is its source
/// times Δτ/μ_i). Doubling two equal layers (the slab is symmetric, so its R is the same from
/// either side), with M = (I − R R)⁻¹ summing the inter-reflections between them:
///     R₂ = R + T M R T,  T₂ = T M T,
///     v = M (t_c + d R r_c)  (diffuse radiance going down at the interface),
///     r_c₂ = r_c + T (d r_c + R v),  t_c₂ = T v + d t_c,  d₂ = d².
/// Starting at Δτ = 2⁻³² (the first-order error, O(Δτ/μ_min), is below 10⁻⁷) the layer doubles
/// until it transmits under 10⁻¹³ of any input: a half-space to double precision. The boundary
/// then reflects the upgoing radiance u back with the exact internal Fresnel reflectance
/// F(μ_i) (total internal reflection below the critical cosine), u = (I − R F)⁻¹ r_c, and what
/// leaves is 2π Σ μ_i w_i (1 − F(μ_i)) u_i per unit entering flux; the radiance along an exit
/// direction is (1 − F(μ)) u(μ) / η² outside (the n² law).

#include <lucent/dipole/HalfSpace.h>

#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/core/Quadrature.h>

#include <Eigen/Dense>

#include <cmath>

namespace lucent::dipole {

HalfSpaceExitance halfSpaceExitance(double albedo, double eta, double mu0,
                                    const std::vector<double>& exitCosines, int nodes) {
    LUCENT_CHECK(std::isfinite(albedo) && albedo >= 0.0 && albedo <= 1.0,
                 "halfSpaceExitance: albedo must be in [0, 1] (got ", albedo, ")");
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0,
                 "halfSpaceExitance: eta must be in [1, 3] (got ", eta, ")");
    LUCENT_CHECK(std::isfinite(mu0) && mu0 > 0.0 && mu0 <= 1.0,
                 "halfSpaceExitance: mu0 must be in (0, 1] (got ", mu0, ")");
    LUCENT_CHECK(nodes >= 2 && nodes <= 256, "halfSpaceExitance: nodes must be in [2, 256] (got ",
                 nodes, ")");
    for (double t : exitCosines)
        LUCENT_CHECK(std::isfinite(t) && t > 0.0 && t <= 1.0,
                     "halfSpaceExitance: exit cosines must be in (0, 1] (got ", t, ")");
    HalfSpaceExitance out;
    out.radiance.assign(exitCosines.size(), 0.0);
    if (albedo == 0.0)
        return out;
    // No absorption: all light returns. The radiance's shape is the limit's, solved just below.
    const bool conservative = albedo == 1.0;
    const double a = conservative ? 1.0 - 1e-10 : albedo;

    // Nodes on (0, 1], split at the critical cosine μ_c inside, below which F = 1 (total
    // internal reflection). Above it the transmittance is smooth in the outside cosine
    // t = η √(μ² − μ_c²), not in μ (it has a square-root edge at μ_c), so those nodes are
    // Gauss–Legendre in t: μ = √(μ_c² + t²/η²), dμ = t/(η² μ) dt. At η = 1 both are plain
    // Gauss–Legendre in μ. The requested exit directions follow with weight 0: they receive
    // light but send none into the sums, so the solution is the same with or without them.
    const double muCritical = eta > 1.0 ? std::sqrt(1.0 - 1.0 / (eta * eta)) : 0.0;
    const auto insideCosine = [&](double t) {
        return std::sqrt(muCritical * muCritical + t * t / (eta * eta));
    };
    const QuadratureRule unit = gaussLegendre(nodes);
    QuadratureRule rule = unit.mappedTo(0.0, 1.0);
    for (size_t k = 0; k < rule.x.size(); ++k) {
        const double t = rule.x[k];
        rule.x[k] = insideCosine(t);
        rule.w[k] *= t / (eta * eta * rule.x[k]);
    }
    if (muCritical > 0.0) {
        const QuadratureRule low = unit.mappedTo(0.0, muCritical);
        rule.x.insert(rule.x.begin(), low.x.begin(), low.x.end());
        rule.w.insert(rule.w.begin(), low.w.begin(), low.w.end());
    }
    const Eigen::Index weighted = Eigen::Index(rule.x.size());
    for (double t : exitCosines) {
        rule.x.push_back(insideCosine(t));
        rule.w.push_back(0.0);
    }
    const Eigen::Index n = Eigen::Index(rule.x.size());
    const Eigen::Map<const Eigen::VectorXd> mu(rule.x.data(), n), w(rule.w.data(), n);

    const double dtau = std::ldexp(1.0, -32);  // the start layer's optical thickness
    Eigen::MatrixXd R(n, n), T(n, n);
    Eigen::VectorXd rc(n);
    for (Eigen::Index i = 0; i < n; ++i) {
        for (Eigen::Index j = 0; j < n; ++j)
            R(i, j) = a * dtau * w(j) / (2.0 * mu(i));
        rc(i) = a * dtau / (4.0 * M_PI * mu0 * mu(i));
    }
    T = R;
    T.diagonal() += (-dtau * mu.cwiseInverse()).array().exp().matrix();
    Eigen::VectorXd tc = rc;
    double d = std::exp(-dtau / mu0);

    // Flux a layer passes on, per unit flux in: the largest over the (weighted) diffuse input
    // directions and the beam's (direct plus diffuse).
    const Eigen::VectorXd fluxWeight = mu.cwiseProduct(w);
    const auto transmitted = [&] {
        const Eigen::VectorXd columns = (fluxWeight.transpose() * T.leftCols(weighted))
                                            .transpose()
                                            .cwiseQuotient(fluxWeight.head(weighted));
        return std::max(columns.maxCoeff(), d + 2.0 * M_PI * fluxWeight.dot(tc));
    };
    const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(n, n);
    int doublings = 0;
    for (; doublings < 200 && transmitted() > 1e-13; ++doublings) {
        const Eigen::PartialPivLU<Eigen::MatrixXd> interReflections(identity - R * R);
        const Eigen::VectorXd down = interReflections.solve(tc + d * (R * rc));
        const Eigen::VectorXd up = d * rc + R * down;
        rc += T * up;
        tc = T * down + d * tc;
        d *= d;
        R += T * interReflections.solve(R * T);
        T = T * interReflections.solve(T);
    }
    LUCENT_ASSERT(doublings < 200);

    Eigen::VectorXd fresnel(n);
    for (Eigen::Index i = 0; i < n; ++i)
        fresnel(i) = fresnelDielectric(mu(i), 1.0 / eta);
    const Eigen::VectorXd up = (identity - R * fresnel.asDiagonal()).partialPivLu().solve(rc);
    const Eigen::VectorXd leaving = (Eigen::VectorXd::Ones(n) - fresnel).cwiseProduct(up);
    const double reflectance = 2.0 * M_PI * fluxWeight.dot(leaving);
    const double scale = conservative ? 1.0 / reflectance : 1.0;
    out.reflectance = conservative ? 1.0 : reflectance;
    for (size_t k = 0; k < exitCosines.size(); ++k)
        out.radiance[k] = scale * leaving(weighted + Eigen::Index(k)) / (eta * eta);
    return out;
}

double halfSpaceReflectance(double albedo, double eta, double mu0, int nodes) {
    return halfSpaceExitance(albedo, eta, mu0, {}, nodes).reflectance;
}

}  // namespace lucent::dipole
