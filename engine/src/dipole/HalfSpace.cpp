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
///
/// Layers of different media (layeredHalfSpaceReflectance) are slabs doubled to their optical
/// thickness from a start layer of at most 2⁻³², stacked from the bottom up by the adding
/// equations (van de Hulst 1980 §5.3; Prahl 1995 Eq. 5.22–5.25): with the top slab's operators
/// R₁, T₁, r_c₁, t_c₁, d₁ and what lies below it R₂, r_c₂ (a half-space transmits nothing), the
/// radiance going up at the interface is u = (I − R₂R₁)⁻¹ (R₂ t_c₁ + d₁ r_c₂), and the stack is
///     R = R₁ + T₁ (I − R₂R₁)⁻¹ R₂ T₁,  r_c = r_c₁ + T₁ u
/// (the slab is symmetric, so R₁ seen from below is R₁). The media are index-matched inside:
/// the beam keeps its cosine μ₀ across the interfaces.

#include <lucent/dipole/HalfSpace.h>

#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/core/Quadrature.h>

#include <Eigen/Dense>

#include <cmath>

namespace lucent::dipole {

namespace {

/// The polar-cosine quadrature inside the boundary, with the exit directions appended at
/// weight 0 (see halfSpaceExitance).
struct BoundaryQuadrature {
    Eigen::VectorXd mu, w;
    Eigen::Index weighted = 0;  ///< nodes that carry weight; the exit directions follow
};

BoundaryQuadrature boundaryQuadrature(double eta, int nodes,
                                      const std::vector<double>& exitCosines) {
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
    BoundaryQuadrature q;
    q.weighted = Eigen::Index(rule.x.size());
    for (double t : exitCosines) {
        rule.x.push_back(insideCosine(t));
        rule.w.push_back(0.0);
    }
    q.mu = Eigen::Map<const Eigen::VectorXd>(rule.x.data(), Eigen::Index(rule.x.size()));
    q.w = Eigen::Map<const Eigen::VectorXd>(rule.w.data(), Eigen::Index(rule.w.size()));
    return q;
}

/// A layer's operators on radiance at the nodes, and its response to the unit beam at μ₀.
struct LayerOperators {
    Eigen::MatrixXd R, T;
    Eigen::VectorXd rc, tc;
    double d = 1.0;  ///< direct transmission of the beam
};

/// Flux a layer passes on, per unit flux in: the largest over the (weighted) diffuse input
/// directions and the beam's (direct plus diffuse).
double transmitted(const LayerOperators& L, const BoundaryQuadrature& q) {
    const Eigen::VectorXd fluxWeight = q.mu.cwiseProduct(q.w);
    const Eigen::VectorXd columns = (fluxWeight.transpose() * L.T.leftCols(q.weighted))
                                        .transpose()
                                        .cwiseQuotient(fluxWeight.head(q.weighted));
    return std::max(columns.maxCoeff(), L.d + 2.0 * M_PI * fluxWeight.dot(L.tc));
}

/// A slab of albedo `a` and optical thickness `tau` (infinite: a half-space, doubled until it
/// transmits under 10⁻¹³ of any input), by doubling from a first-order start layer of at most
/// 2⁻³².
LayerOperators doubledLayer(double a, double tau, const BoundaryQuadrature& q, double mu0) {
    const Eigen::Index n = q.mu.size();
    const bool halfSpace = std::isinf(tau);
    // Start thickness: 2⁻³² for a half-space, else tau / 2^k with k doublings to reach it.
    int doublingsToTau = 0;
    double dtau = std::ldexp(1.0, -32);
    if (!halfSpace) {
        doublingsToTau = std::max(0, int(std::ceil(std::log2(tau))) + 32);
        dtau = std::ldexp(tau, -doublingsToTau);
    }
    LayerOperators L;
    L.R.resize(n, n);
    L.rc.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) {
        for (Eigen::Index j = 0; j < n; ++j)
            L.R(i, j) = a * dtau * q.w(j) / (2.0 * q.mu(i));
        L.rc(i) = a * dtau / (4.0 * M_PI * mu0 * q.mu(i));
    }
    L.T = L.R;
    L.T.diagonal() += (-dtau * q.mu.cwiseInverse()).array().exp().matrix();
    L.tc = L.rc;
    L.d = std::exp(-dtau / mu0);
    const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(n, n);
    for (int doublings = 0;; ++doublings) {
        if (halfSpace ? transmitted(L, q) <= 1e-13 : doublings == doublingsToTau)
            break;
        // Past the point where it transmits nothing, further doubling changes nothing.
        if (!halfSpace && transmitted(L, q) <= 1e-13)
            break;
        LUCENT_ASSERT(doublings < 300);
        const Eigen::PartialPivLU<Eigen::MatrixXd> interReflections(identity - L.R * L.R);
        const Eigen::VectorXd down = interReflections.solve(L.tc + L.d * (L.R * L.rc));
        const Eigen::VectorXd up = L.d * L.rc + L.R * down;
        L.rc += L.T * up;
        L.tc = L.T * down + L.d * L.tc;
        L.d *= L.d;
        L.R += L.T * interReflections.solve(L.R * L.T);
        L.T = L.T * interReflections.solve(L.T);
    }
    return L;
}

/// `top` added over the half-space `bottom` (the adding equations of the file comment). The
/// stack is a half-space too: it transmits nothing (T, t_c and d are zero).
LayerOperators stackOver(const LayerOperators& top, const LayerOperators& bottom) {
    const Eigen::Index n = top.R.rows();
    const Eigen::PartialPivLU<Eigen::MatrixXd> interReflections(Eigen::MatrixXd::Identity(n, n) -
                                                                bottom.R * top.R);
    const Eigen::VectorXd up = interReflections.solve(bottom.R * top.tc + top.d * bottom.rc);
    LayerOperators out;
    out.R = top.R + top.T * interReflections.solve(bottom.R * top.T);
    out.rc = top.rc + top.T * up;
    out.T = Eigen::MatrixXd::Zero(n, n);
    out.tc = Eigen::VectorXd::Zero(n);
    out.d = 0.0;
    return out;
}

/// The exact internal Fresnel reflectance at each node (total internal reflection below the
/// critical cosine).
Eigen::VectorXd internalFresnel(const BoundaryQuadrature& q, double eta) {
    Eigen::VectorXd fresnel(q.mu.size());
    for (Eigen::Index i = 0; i < q.mu.size(); ++i)
        fresnel(i) = fresnelDielectric(q.mu(i), 1.0 / eta);
    return fresnel;
}

/// What leaves through the boundary: the exact internal Fresnel reflection returns the
/// upgoing radiance u = (I − R F)⁻¹ r_c; (reflectance, outside radiance along the exit
/// directions).
HalfSpaceExitance throughBoundary(const LayerOperators& L, const BoundaryQuadrature& q, double eta,
                                  size_t exitCount) {
    const Eigen::Index n = q.mu.size();
    const Eigen::VectorXd fresnel = internalFresnel(q, eta);
    const Eigen::VectorXd up =
        (Eigen::MatrixXd::Identity(n, n) - L.R * fresnel.asDiagonal()).partialPivLu().solve(L.rc);
    const Eigen::VectorXd leaving = (Eigen::VectorXd::Ones(n) - fresnel).cwiseProduct(up);
    HalfSpaceExitance out;
    out.reflectance = 2.0 * M_PI * q.mu.cwiseProduct(q.w).dot(leaving);
    out.radiance.resize(exitCount);
    for (size_t k = 0; k < exitCount; ++k)
        out.radiance[k] = leaving(q.weighted + Eigen::Index(k)) / (eta * eta);
    return out;
}

void checkCommon(const char* what, double eta, double mu0, int nodes) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0, what,
                 ": eta must be in [1, 3] (got ", eta, ")");
    LUCENT_CHECK(std::isfinite(mu0) && mu0 > 0.0 && mu0 <= 1.0, what,
                 ": mu0 must be in (0, 1] (got ", mu0, ")");
    LUCENT_CHECK(nodes >= 2 && nodes <= 256, what, ": nodes must be in [2, 256] (got ", nodes, ")");
}

void checkExitCosines(const char* what, const std::vector<double>& exitCosines) {
    for (double t : exitCosines)
        LUCENT_CHECK(std::isfinite(t) && t > 0.0 && t <= 1.0, what,
                     ": exit cosines must be in (0, 1] (got ", t, ")");
}

void checkAlbedo(const char* what, double albedo) {
    LUCENT_CHECK(std::isfinite(albedo) && albedo >= 0.0 && albedo <= 1.0, what,
                 ": albedo must be in [0, 1] (got ", albedo, ")");
}

}  // namespace

HalfSpaceExitance halfSpaceExitance(double albedo, double eta, double mu0,
                                    const std::vector<double>& exitCosines, int nodes) {
    checkAlbedo("halfSpaceExitance", albedo);
    checkCommon("halfSpaceExitance", eta, mu0, nodes);
    checkExitCosines("halfSpaceExitance", exitCosines);
    HalfSpaceExitance out;
    out.radiance.assign(exitCosines.size(), 0.0);
    if (albedo == 0.0)
        return out;
    // No absorption: all light returns. The radiance's shape is the limit's, solved just below.
    const bool conservative = albedo == 1.0;
    const double a = conservative ? 1.0 - 1e-10 : albedo;
    const BoundaryQuadrature q = boundaryQuadrature(eta, nodes, exitCosines);
    out = throughBoundary(doubledLayer(a, INFINITY, q, mu0), q, eta, exitCosines.size());
    if (conservative) {
        for (double& r : out.radiance)
            r /= out.reflectance;
        out.reflectance = 1.0;
    }
    return out;
}

double halfSpaceReflectance(double albedo, double eta, double mu0, int nodes) {
    return halfSpaceExitance(albedo, eta, mu0, {}, nodes).reflectance;
}

double layeredHalfSpaceReflectance(const std::vector<HalfSpaceLayer>& layers, double eta,
                                   double mu0, int nodes) {
    LUCENT_CHECK(!layers.empty(), "layeredHalfSpaceReflectance: no layers");
    checkCommon("layeredHalfSpaceReflectance", eta, mu0, nodes);
    for (size_t i = 0; i < layers.size(); ++i) {
        checkAlbedo("layeredHalfSpaceReflectance", layers[i].albedo);
        LUCENT_CHECK(
            i + 1 == layers.size() ||
                (std::isfinite(layers[i].opticalThickness) && layers[i].opticalThickness >= 0.0),
            "layeredHalfSpaceReflectance: layer ", i,
            ": optical thickness must be finite and >= 0 (got ", layers[i].opticalThickness, ")");
    }
    const BoundaryQuadrature q = boundaryQuadrature(eta, nodes, {});
    // A conservative medium is solved just below albedo 1, as in halfSpaceExitance.
    const auto solvable = [](double a) { return std::min(a, 1.0 - 1e-10); };
    LayerOperators stack = doubledLayer(solvable(layers.back().albedo), INFINITY, q, mu0);
    for (size_t i = layers.size() - 1; i-- > 0;) {
        if (layers[i].opticalThickness == 0.0)
            continue;
        stack = stackOver(
            doubledLayer(solvable(layers[i].albedo), layers[i].opticalThickness, q, mu0), stack);
    }
    return throughBoundary(stack, q, eta, 0).reflectance;
}

SlabExitance slabExitance(double albedo, double eta, double opticalThickness, double mu0,
                          const std::vector<double>& exitCosines, int nodes) {
    checkAlbedo("slabExitance", albedo);
    checkCommon("slabExitance", eta, mu0, nodes);
    checkExitCosines("slabExitance", exitCosines);
    LUCENT_CHECK(std::isfinite(opticalThickness) && opticalThickness >= 0.0,
                 "slabExitance: optical thickness must be finite and >= 0 (got ", opticalThickness,
                 ")");
    // The unscattered beam bounces between the faces with the internal Fresnel reflectance at
    // its own cosine: the flux going down at the top is 1 + (F d)² + (F d)⁴ + … and going up at
    // the bottom F d times that.
    const double beamFresnel = fresnelDielectric(mu0, 1.0 / eta);
    const double direct = std::exp(-opticalThickness / mu0);
    const double down = 1.0 / (1.0 - beamFresnel * beamFresnel * direct * direct);
    const double up = beamFresnel * direct * down;
    SlabExitance out;
    out.reflectedRadiance.assign(exitCosines.size(), 0.0);
    out.transmittedRadiance.assign(exitCosines.size(), 0.0);
    out.directTransmittance = (1.0 - beamFresnel) * direct * down;
    out.directReflectance = (1.0 - beamFresnel) * direct * up;
    if (albedo == 0.0 || opticalThickness == 0.0)
        return out;
    const BoundaryQuadrature q = boundaryQuadrature(eta, nodes, exitCosines);
    const LayerOperators L = doubledLayer(std::min(albedo, 1.0 - 1e-10), opticalThickness, q, mu0);
    // The diffuse radiance leaving the layer upward at the top (u) and downward at the bottom
    // (v); each face sends F u (F v) back in. The layer is symmetric, so the beam going up
    // scatters as the one going down with the faces swapped (r_c down, t_c up):
    //     u = R F u + T F v + r_c·down + t_c·up,   v = T F u + R F v + t_c·down + r_c·up.
    const Eigen::Index n = q.mu.size();
    const Eigen::VectorXd fresnel = internalFresnel(q, eta);
    const Eigen::MatrixXd RF = L.R * fresnel.asDiagonal(), TF = L.T * fresnel.asDiagonal();
    Eigen::MatrixXd system = Eigen::MatrixXd::Identity(2 * n, 2 * n);
    system.topLeftCorner(n, n) -= RF;
    system.topRightCorner(n, n) -= TF;
    system.bottomLeftCorner(n, n) -= TF;
    system.bottomRightCorner(n, n) -= RF;
    Eigen::VectorXd source(2 * n);
    source.head(n) = L.rc * down + L.tc * up;
    source.tail(n) = L.tc * down + L.rc * up;
    const Eigen::VectorXd radiance = system.partialPivLu().solve(source);
    const Eigen::VectorXd leaving = Eigen::VectorXd::Ones(n) - fresnel;
    const Eigen::VectorXd leavingFlux = q.mu.cwiseProduct(q.w).cwiseProduct(leaving);
    out.reflectance = 2.0 * M_PI * leavingFlux.dot(radiance.head(n));
    out.transmittance = 2.0 * M_PI * leavingFlux.dot(radiance.tail(n));
    for (size_t k = 0; k < exitCosines.size(); ++k) {
        const Eigen::Index i = q.weighted + Eigen::Index(k);
        out.reflectedRadiance[k] = leaving(i) * radiance(i) / (eta * eta);
        out.transmittedRadiance[k] = leaving(i) * radiance(n + i) / (eta * eta);
    }
    return out;
}

}  // namespace lucent::dipole
