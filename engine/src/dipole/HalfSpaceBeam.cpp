// SPDX-License-Identifier: MIT
/// @file
/// @brief Pencil-beam Monte Carlo of the half-space and radial comparisons (HalfSpaceBeam.h).
/// Written apart from the path tracer on purpose (its own generator, Fresnel and geometry): it is
/// the independent solver the profiles are measured against.

#include <lucent/dipole/HalfSpaceBeam.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Quadrature.h>
#include <lucent/dipole/AnchorProfiles.h>

#include <algorithm>
#include <cmath>

namespace lucent::dipole {
namespace {
constexpr double PI_D = 3.14159265358979323846;

/// SplitMix64 (Steele, Lea & Flood 2014): one 64-bit state, passes BigCrush; enough for a
/// reference walk, and deliberately not the renderer's generator.
struct SplitMix64 {
    uint64_t state;
    uint64_t next() {
        uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    /// Uniform in [0, 1) with 53 random bits.
    double uniform() { return double(next() >> 11) * 0x1.0p-53; }
};

/// Unpolarised Fresnel reflectance for light inside the medium meeting the boundary at cosine
/// `cosInside`, relative index `eta` = n_inside / n_outside (Born & Wolf §1.5.2).
double reflectanceLeaving(double cosInside, double eta) {
    const double sinOut2 = eta * eta * (1.0 - cosInside * cosInside);
    if (sinOut2 >= 1.0)
        return 1.0;
    const double cosOut = std::sqrt(1.0 - sinOut2);
    // n₁ = η (inside), n₂ = 1 (outside).
    const double rs = (eta * cosInside - cosOut) / (eta * cosInside + cosOut);
    const double rp = (cosInside - eta * cosOut) / (cosInside + eta * cosOut);
    return 0.5 * (rs * rs + rp * rp);
}

/// Depth of the layer under the surface whose track lengths estimate the flux density there
/// (mfp): thin against the rings it is read in (≥ 0.3 mfp apart beyond 1 mfp) and thick enough
/// to be crossed by many flights.
constexpr double SURFACE_LAYER = 0.05;

struct Tally {
    std::vector<double> sum, sumSq, singleSum, singleSumSq, cosSum, radialSum, layerRadial,
        layerNormal;
    double beyond = 0.0, total = 0.0, totalSq = 0.0, totalCos = 0.0;
    explicit Tally(size_t rings)
        : sum(rings, 0.0),
          sumSq(rings, 0.0),
          singleSum(rings, 0.0),
          singleSumSq(rings, 0.0),
          cosSum(rings, 0.0),
          radialSum(rings, 0.0),
          layerRadial(rings, 0.0),
          layerNormal(rings, 0.0) {}
};

size_t ringOf(const std::vector<double>& edges, double r) {
    return size_t(std::upper_bound(edges.begin(), edges.end(), r) - edges.begin());
}

/// The part of the flight from (x, y, z) along (dx, dy, dz) of length `length` that lies in the
/// surface layer z ∈ [−SURFACE_LAYER, 0]: its track length times the direction's radial and
/// normal components, in the ring of its midpoint (the layer is thin against the rings).
void tallyLayer(const std::vector<double>& edges, Tally& t, double w, double x, double y, double z,
                double dx, double dy, double dz, double length) {
    double s0 = 0.0, s1 = length;
    if (dz == 0.0) {
        if (z < -SURFACE_LAYER)
            return;
    } else {
        const double sLayer = (-SURFACE_LAYER - z) / dz;  // where z(s) = −SURFACE_LAYER
        if (dz > 0.0)
            s0 = std::max(s0, sLayer);
        else
            s1 = std::min(s1, sLayer);
    }
    if (!(s1 > s0))
        return;
    const double sm = 0.5 * (s0 + s1), xm = x + sm * dx, ym = y + sm * dy;
    const double r = std::sqrt(xm * xm + ym * ym);
    const size_t ring = ringOf(edges, r);
    if (ring >= edges.size() || !(r > 0.0))
        return;
    const double l = w * (s1 - s0);
    t.layerRadial[ring] += l * (dx * xm + dy * ym) / r;
    t.layerNormal[ring] += l * dz;
}

/// One photon: enters at the origin along −z (the medium is z < 0), returns nothing; adds its
/// exit weight to the tally.
void walk(SplitMix64& rng, double albedo, double eta, const std::vector<double>& edges, Tally& t) {
    double x = 0.0, y = 0.0, z = 0.0, dx = 0.0, dy = 0.0, dz = -1.0, w = 1.0;
    int scatterings = 0;
    for (int64_t step = 0; step < 100000000; ++step) {
        const double s = -std::log1p(-rng.uniform());
        const double nz = z + s * dz;
        if (nz >= 0.0) {  // reaches the boundary first: stop on it
            const double d = -z / dz;
            tallyLayer(edges, t, w, x, y, z, dx, dy, dz, d);
            x += d * dx;
            y += d * dy;
            z = 0.0;
            if (rng.uniform() < reflectanceLeaving(dz, eta)) {
                dz = -dz;  // mirror: heads back in, the next flight starts on the boundary
                continue;
            }
            const double r = std::sqrt(x * x + y * y);
            // Outside cosine of the refracted exit direction (Snell, n_inside = η).
            const double cosOut = std::sqrt(std::max(0.0, 1.0 - eta * eta * (1.0 - dz * dz)));
            t.totalCos += w * cosOut;
            const size_t ring = ringOf(edges, r);
            t.total += w;
            t.totalSq += w * w;
            if (ring >= edges.size()) {
                t.beyond += w;
                return;
            }
            t.sum[ring] += w;
            t.sumSq[ring] += w * w;
            t.cosSum[ring] += w * cosOut;
            // Outside, the tangential part of the direction is η times the inside one (Snell).
            if (r > 0.0)
                t.radialSum[ring] += w * eta * (dx * x + dy * y) / r;
            if (scatterings == 1) {
                t.singleSum[ring] += w;
                t.singleSumSq[ring] += w * w;
            }
            return;
        }
        tallyLayer(edges, t, w, x, y, z, dx, dy, dz, s);
        x += s * dx;
        y += s * dy;
        z = nz;
        // Scatter: weight times the albedo, a new direction uniform on the sphere.
        ++scatterings;
        w *= albedo;
        if (w < 1e-2) {  // Russian roulette: unbiased, keeps the weights bounded
            if (rng.uniform() >= 0.1)
                return;
            w *= 10.0;
        }
        dz = 2.0 * rng.uniform() - 1.0;
        const double phi = 2.0 * PI_D * rng.uniform();
        const double sinT = std::sqrt(std::max(0.0, 1.0 - dz * dz));
        dx = sinT * std::cos(phi);
        dy = sinT * std::sin(phi);
    }
}

double stdError(double sum, double sumSq, int64_t n) {
    const double mean = sum / double(n);
    return n > 1 ? std::sqrt(std::max(0.0, sumSq / double(n) - mean * mean) / double(n - 1)) : 0.0;
}

/// ∫_a^b f(r) 2πr dr by composite Gauss–Legendre uniform in log r.
double ringIntegral(const std::function<double(double)>& f, double a, double b, int panels) {
    static const QuadratureRule g = gaussLegendre(8);
    const double la = std::log(a), step = (std::log(b) - la) / panels;
    double sum = 0.0;
    for (int p = 0; p < panels; ++p)
        for (size_t i = 0; i < g.x.size(); ++i) {
            const double r = std::exp(la + step * (p + 0.5 * (g.x[i] + 1.0)));
            sum += 0.5 * step * g.w[i] * 2.0 * PI_D * r * r * f(r);
        }
    return sum;
}

/// Radius at which the cumulative fraction reaches q: log-interpolated between ring edges
/// (linear in r inside the first ring). `fractions` has one entry per ring plus "beyond".
double quantileRadius(const std::vector<double>& edges, const std::vector<double>& fractions,
                      double q) {
    double below = 0.0;
    for (size_t i = 0; i < edges.size(); ++i) {
        const double next = below + fractions[i];
        if (next >= q && fractions[i] > 0.0) {
            const double f = (q - below) / fractions[i];
            if (i == 0)
                return edges[0] * f;
            return edges[i - 1] * std::pow(edges[i] / edges[i - 1], f);
        }
        below = next;
    }
    return edges.back();
}
}  // namespace

std::vector<double> defaultBeamRings() {
    std::vector<double> edges;
    for (int i = 0; i <= 32; ++i)
        edges.push_back(std::pow(10.0, -2.0 + double(i) / 8.0));
    return edges;
}

HalfSpaceBeamProfile traceHalfSpaceBeam(double albedo, double eta,
                                        const std::vector<double>& ringEdges, int64_t photons,
                                        uint64_t seed) {
    LUCENT_CHECK(std::isfinite(albedo) && albedo >= 0.0 && albedo <= 0.9999,
                 "traceHalfSpaceBeam: the albedo must be in [0, 0.9999] (got ", albedo,
                 "; at 1 the walks' length has no finite mean)");
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.0 && eta <= 3.0,
                 "traceHalfSpaceBeam: eta must be in [1, 3] (got ", eta, ")");
    LUCENT_CHECK(photons >= 1 && photons <= 10000000000LL,
                 "traceHalfSpaceBeam: photons must be in [1, 1e10] (got ", photons, ")");
    LUCENT_CHECK(!ringEdges.empty(), "traceHalfSpaceBeam: no ring edges");
    for (size_t i = 0; i < ringEdges.size(); ++i)
        LUCENT_CHECK(std::isfinite(ringEdges[i]) && ringEdges[i] > 0.0 &&
                         (i == 0 || ringEdges[i] > ringEdges[i - 1]),
                     "traceHalfSpaceBeam: ring edges must be positive, finite and ascending");

    // Fixed chunks with their own streams: the result does not depend on the thread count.
    constexpr int64_t CHUNK = 1 << 15;
    const int64_t chunks = (photons + CHUNK - 1) / CHUNK;
    std::vector<Tally> tallies(size_t(chunks), Tally(ringEdges.size()));
    parallelFor(
        0, chunks,
        [&](int64_t c0, int64_t c1) {
            for (int64_t c = c0; c < c1; ++c) {
                // The chunk's starting state is a SplitMix64 output of (seed, chunk), not an
                // offset along one stream: states a multiple of the increment apart would give
                // chunks the same numbers shifted by a draw (correlated, far noisier than the
                // standard error says).
                SplitMix64 seeder{seed ^ (uint64_t(c) * 0xD1B54A32D192ED03ull)};
                SplitMix64 rng{seeder.next()};
                const int64_t n = std::min(CHUNK, photons - c * CHUNK);
                for (int64_t i = 0; i < n; ++i)
                    walk(rng, albedo, eta, ringEdges, tallies[size_t(c)]);
            }
        },
        1);
    Tally all(ringEdges.size());
    for (const Tally& t : tallies) {  // in chunk order: the same sums on every run
        for (size_t i = 0; i < ringEdges.size(); ++i) {
            all.sum[i] += t.sum[i];
            all.sumSq[i] += t.sumSq[i];
            all.singleSum[i] += t.singleSum[i];
            all.singleSumSq[i] += t.singleSumSq[i];
            all.cosSum[i] += t.cosSum[i];
            all.radialSum[i] += t.radialSum[i];
            all.layerRadial[i] += t.layerRadial[i];
            all.layerNormal[i] += t.layerNormal[i];
        }
        all.totalCos += t.totalCos;
        all.beyond += t.beyond;
        all.total += t.total;
        all.totalSq += t.totalSq;
    }
    HalfSpaceBeamProfile out;
    out.albedo = albedo;
    out.eta = eta;
    out.photons = photons;
    out.ringEdges = ringEdges;
    const double n = double(photons);
    for (size_t i = 0; i < ringEdges.size(); ++i) {
        out.ringFlux.push_back(all.sum[i] / n);
        out.ringStdError.push_back(stdError(all.sum[i], all.sumSq[i], photons));
        out.singleRingFlux.push_back(all.singleSum[i] / n);
        out.singleRingStdError.push_back(stdError(all.singleSum[i], all.singleSumSq[i], photons));
        out.ringMeanExitCosine.push_back(all.sum[i] > 0.0 ? all.cosSum[i] / all.sum[i] : 0.0);
        out.ringMeanExitRadial.push_back(all.sum[i] > 0.0 ? all.radialSum[i] / all.sum[i] : 0.0);
        // Track length per layer depth: the flux density integrated over the ring's area.
        out.ringLayerRadialFlux.push_back(all.layerRadial[i] / (n * SURFACE_LAYER));
        out.ringLayerNormalFlux.push_back(all.layerNormal[i] / (n * SURFACE_LAYER));
    }
    out.surfaceLayerDepth = SURFACE_LAYER;
    out.beyond = all.beyond / n;
    out.total = all.total / n;
    out.totalStdError = stdError(all.total, all.totalSq, photons);
    out.meanExitCosine = all.total > 0.0 ? all.totalCos / all.total : 0.0;
    return out;
}

RadialComparison compareRadial(const HalfSpaceBeamProfile& exact,
                               const std::function<double(double)>& profile, double modelTotal) {
    const std::vector<double>& edges = exact.ringEdges;
    LUCENT_CHECK(!edges.empty() && exact.ringFlux.size() == edges.size() && exact.total > 0.0,
                 "compareRadial: the exact profile is empty");
    LUCENT_CHECK(std::isfinite(modelTotal) && modelTotal > 0.0,
                 "compareRadial: the model's total must be > 0 (got ", modelTotal, ")");
    RadialComparison c;
    // The disc inside the first edge from 10⁻⁹ of it (the profiles' R·r stays bounded at 0);
    // one panel per ring (an eighth of a decade); beyond the last edge to 100× it.
    for (size_t i = 0; i < edges.size(); ++i) {
        const double v = i == 0 ? ringIntegral(profile, 1e-9 * edges[0], edges[0], 18)
                                : ringIntegral(profile, edges[i - 1], edges[i], 1);
        c.ringFlux.push_back(v);
    }
    const double beyond = ringIntegral(profile, edges.back(), 100.0 * edges.back(), 16);
    double modelSum = beyond;
    for (double v : c.ringFlux) {
        LUCENT_CHECK(std::isfinite(v) && v >= 0.0,
                     "compareRadial: the model's ring flux is not finite and >= 0");
        modelSum += v;
    }
    LUCENT_CHECK(std::isfinite(modelSum) && modelSum > 0.0,
                 "compareRadial: the model has no flux in the rings");
    std::vector<double> p, q;  // exact and model fractions, rings then beyond
    double floorSum = 0.0;
    for (size_t i = 0; i < edges.size(); ++i) {
        p.push_back(exact.ringFlux[i] / exact.total);
        q.push_back(c.ringFlux[i] / modelSum);
        floorSum += exact.ringStdError[i];
    }
    p.push_back(exact.beyond / exact.total);
    q.push_back(beyond / modelSum);
    for (size_t i = 0; i < p.size(); ++i)
        c.shapeError += 0.5 * std::abs(q[i] - p[i]);
    c.shapeErrorFloor = 0.5 * floorSum * std::sqrt(2.0 / PI_D) / exact.total;
    c.totalRatio = modelTotal / exact.total;
    c.r50Ratio = quantileRadius(edges, q, 0.5) / quantileRadius(edges, p, 0.5);
    c.r90Ratio = quantileRadius(edges, q, 0.9) / quantileRadius(edges, p, 0.9);
    return c;
}

std::vector<ModelAgainstBeam> compareModelsWithBeam(const ScalarMedium& m,
                                                    const HalfSpaceBeamProfile& exact) {
    const double st = m.sigma_a + m.sigma_s;
    LUCENT_CHECK(st > 0.0 && m.sigma_s > 0.0,
                 "compareModelsWithBeam: the medium must scatter (sigma_s' > 0)");
    const double albedo = m.sigma_s / st;
    LUCENT_CHECK(std::abs(albedo - exact.albedo) <= 1e-6 && std::abs(m.eta - exact.eta) <= 1e-6,
                 "compareModelsWithBeam: the exact profile was traced at albedo ", exact.albedo,
                 ", eta ", exact.eta, ", the medium has ", albedo, ", ", m.eta);
    // R in mfp units: r_mm = r / σt′, R per mfp² = R per mm² / σt′².
    const auto inMfp = [st](auto&& f) {
        return [st, f](double r) { return f(r / st) / (st * st); };
    };
    std::vector<ModelAgainstBeam> rows;
    for (const std::string& name : radialProfileNames()) {
        const NamedRadialProfile p = makeRadialProfile(name, m);
        rows.push_back({name, compareRadial(exact, inMfp(p.R), p.total)});
    }
    return rows;
}

SurfaceLean surfaceLeanWithin(const HalfSpaceBeamProfile& p, double rMin, double rMax) {
    double flux = 0.0, leanFlux = 0.0, radial = 0.0, normal = 0.0;
    for (size_t i = 0; i < p.ringEdges.size() && i < p.ringMeanExitRadial.size(); ++i) {
        const double inner = i == 0 ? 0.0 : p.ringEdges[i - 1];
        if (inner >= rMin && p.ringEdges[i] <= rMax) {
            flux += p.ringFlux[i];
            leanFlux += p.ringFlux[i] * p.ringMeanExitRadial[i];
            radial += p.ringLayerRadialFlux[i];
            normal += p.ringLayerNormalFlux[i];
        }
    }
    SurfaceLean s;
    if (flux > 0.0)
        s.lean = leanFlux / flux;
    if (normal > 0.0)
        s.fluxRatio = radial / normal;
    return s;
}

double meanExitCosineWithin(const HalfSpaceBeamProfile& p, double rMin, double rMax) {
    double flux = 0.0, cosFlux = 0.0;
    for (size_t i = 0; i < p.ringEdges.size() && i < p.ringMeanExitCosine.size(); ++i) {
        const double inner = i == 0 ? 0.0 : p.ringEdges[i - 1];
        if (inner >= rMin && p.ringEdges[i] <= rMax) {
            flux += p.ringFlux[i];
            cosFlux += p.ringFlux[i] * p.ringMeanExitCosine[i];
        }
    }
    return flux > 0.0 ? cosFlux / flux : 0.0;
}

}  // namespace lucent::dipole
