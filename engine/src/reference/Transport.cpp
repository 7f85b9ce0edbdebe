// SPDX-License-Identifier: MIT
/// @file
/// @brief The reference path tracer's transport kernels (see Transport.h, docs/reference.md).
///
/// Literature: delta tracking — Woodcock et al. 1965; Novák et al., "Monte Carlo methods for
/// volumetric light transport simulation", CGF 2018 (STAR), Sec. 4.1 (Eq. 18: accept a
/// tentative collision with probability σt(x)/σ̄). Ratio tracking — Novák, Selle & Jarosz,
/// "Residual ratio tracking", TOG 2014, Sec. 3 (Eq. 7: T = Π (1 − σt(xᵢ)/σ̄)). Free-flight
/// sampling of a constant σ̄: t = −ln(1 − u)/σ̄ (STAR Eq. 12). HG phase function: Henyey &
/// Greenstein 1941 (lucent/core/SphericalHarmonics.h hgPhase). Fresnel: Born & Wolf; pbrt-v3
/// Eq. 8.1–8.2.

#include <lucent/core/Error.h>
#include <lucent/core/Sampling.h>
#include <lucent/core/SphericalHarmonics.h>
#include <lucent/reference/Transport.h>

namespace lucent {

namespace {

/// Surface interactions without a scattering event after which a path is dropped (a ray
/// trapped by total internal reflection in a vacuum pocket; never reached in practice).
constexpr int MAX_SURFACE_EVENTS = 1 << 16;
/// Weight-window Russian roulette threshold (unbiased: survivors get weight / q).
constexpr float ROULETTE_WEIGHT = 0.5f;
/// Ratio-tracking roulette threshold on the running transmittance.
constexpr float RATIO_ROULETTE = 0.1f;

Vector3f reflect(const Vector3f& d, const Normal3f& n) {
    return d - 2.f * glm::dot(d, n) * n;
}

/// Refraction of unit `d` through a surface whose unit normal `n` faces the incident side,
/// relative index eta = η_t/η_i (Snell's law, vector form: pbrt-v3 Eq. 8.8).
/// Returns nothing for total internal reflection.
std::optional<Vector3f> refract(const Vector3f& d, const Normal3f& n, float eta) {
    const float cosI = -glm::dot(d, n);
    const float inv = 1.f / eta;
    const float k = 1.f - inv * inv * (1.f - cosI * cosI);
    if (k < 0.f)
        return std::nullopt;
    return glm::normalize(inv * d + (inv * cosI - std::sqrt(k)) * n);
}

/// Nearest t > 0 where o + t·d (unit d) meets a sphere, INF if none.
float intersectSphere(const Point3f& o, const Vector3f& d, const Point3f& c, float r) {
    const Vector3f oc = o - c;
    const float b = glm::dot(oc, d);
    const float cc = glm::dot(oc, oc) - r * r;
    const float disc = b * b - cc;
    if (disc < 0.f)
        return INF;
    const float s = std::sqrt(disc);
    const float t0 = -b - s, t1 = -b + s;
    if (t0 > 0.f)
        return t0;
    if (t1 > 0.f)
        return t1;
    return INF;
}

float exponentialStep(Pcg32& rng, float majorant) {
    // Free flight in a medium of constant σ̄: t = −ln(1 − u)/σ̄ (STAR Eq. 12).
    return -std::log1p(-rng.uniform()) / majorant;
}

/// Roulette on `weight`; returns false when the path is terminated.
bool roulette(float& weight, Pcg32& rng) {
    if (weight >= ROULETTE_WEIGHT)
        return true;
    const float q = weight / ROULETTE_WEIGHT;
    if (rng.uniform() >= q)
        return false;
    weight = ROULETTE_WEIGHT;
    return true;
}

/// A light sampled from a point x inside the medium (next-event estimation): direction wi
/// towards the light, distance (INF for directional) and the radiance-over-pdf term per
/// channel (irradiance-like, W/mm²). Shared by the per-channel and spectral-MIS estimators so
/// both consume the random numbers identically.
struct LightSample {
    Vector3f wi{0.f};
    float dist = 0.f;
    Rgb le{0.f};
};

std::optional<LightSample> sampleLightFrom(const Light& light, const Point3f& x, Pcg32& rng) {
    Vector3f wi(0.f);
    float dist = 0.f;
    Rgb le(0.f);
    switch (light.type) {
        case Light::Type::Point:
        case Light::Type::Spot: {
            const Vector3f toLight = light.position - x;
            const float d2 = glm::dot(toLight, toLight);
            if (!(d2 > 0.f))
                return std::nullopt;
            dist = std::sqrt(d2);
            wi = toLight / dist;
            le = light.intensityToward(-wi) / d2;  // I/r² (inverse square law)
            break;
        }
        case Light::Type::Directional:
            wi = -glm::normalize(light.direction);
            dist = INF;
            le = light.intensity;
            break;
        case Light::Type::Sphere: {
            const Vector3f toC = light.position - x;
            const float d2 = glm::dot(toC, toC);
            const float r2 = light.radius * light.radius;
            if (d2 <= r2)
                return std::nullopt;
            // Cone sampling, pdf 1/(2π(1 − cos θmax)) (pbrt-v3 Sec. 14.2.3).
            const float cosMax = std::sqrt(std::max(0.f, 1.f - r2 / d2));
            const float u0 = rng.uniform(), u1 = rng.uniform();
            const float cosT = 1.f - u0 * (1.f - cosMax);
            const float sinT = std::sqrt(std::max(0.f, 1.f - cosT * cosT));
            const float phi = 2.f * PI * u1;
            const Frame frame(toC / std::sqrt(d2));
            wi = glm::normalize(frame.toWorld({sinT * std::cos(phi), sinT * std::sin(phi), cosT}));
            dist = intersectSphere(x, wi, light.position, light.radius);
            if (!std::isfinite(dist))
                dist = std::sqrt(d2);
            le = light.intensity * (2.f * PI * (1.f - cosMax));
            break;
        }
        default:
            return std::nullopt;
    }
    return LightSample{wi, dist, le};
}

/// Next-event estimation from a real collision at x (inside the object): Σ over lights of
/// phase · transmittance · radiance / pdf. `dirIn` is the path's travel direction at x.
float directLighting(const VolumeScene& scene, const Point3f& x, const Vector3f& dirIn, float g,
                     int ch, Pcg32& rng, const TransportOptions& options, TrackingStats* stats) {
    float sum = 0.f;
    for (const Light& light : scene.lights()) {
        const std::optional<LightSample> ls = sampleLightFrom(light, x, rng);
        if (!ls)
            continue;
        const Vector3f wi = ls->wi;
        const float dist = ls->dist, le = ls->le[ch];
        if (!(le > 0.f))
            continue;
        // HG phase value for the angle between the path's travel direction and wi (the
        // light's travel direction −wi against −dirIn gives the same cosine).
        const float phase = hgPhase(g, glm::dot(dirIn, wi));
        if (!(phase > 0.f))
            continue;
        const float tr =
            shadowTransmittance(scene, x, wi, dist, /*pInside=*/true, ch, rng, options, stats);
        sum += phase * tr * le;
    }
    return sum;
}

}  // namespace

float fresnelDielectric(float cosI, float eta) {
    cosI = std::clamp(cosI, 0.f, 1.f);
    // Snell: sin θt = sin θi / η (η = η_t/η_i).
    const float sin2T = (1.f - cosI * cosI) / (eta * eta);
    if (sin2T >= 1.f)
        return 1.f;  // total internal reflection
    const float cosT = std::sqrt(1.f - sin2T);
    // Fresnel equations for s and p polarisation, divided through by η_i (pbrt-v3 Eq. 8.1–8.2).
    const float rs = (cosI - eta * cosT) / (cosI + eta * cosT);
    const float rp = (eta * cosI - cosT) / (eta * cosI + cosT);
    return 0.5f * (rs * rs + rp * rp);
}

VolumeScene::VolumeScene(const TriangleMesh& mesh, GridMedium medium, std::vector<Light> lights)
    : m_boundary(mesh), m_medium(std::move(medium)), m_lights(std::move(lights)) {
    for (size_t i = 0; i < m_lights.size(); ++i) {
        const Light& l = m_lights[i];
        LUCENT_CHECK(isFinite(l.position) && isFinite(l.direction) && isFinite(l.intensity) &&
                         l.intensity.r >= 0.f && l.intensity.g >= 0.f && l.intensity.b >= 0.f,
                     "lights[", i,
                     "]: position, direction and intensity must be finite, "
                     "intensity ≥ 0");
        if (l.type == Light::Type::Directional)
            LUCENT_CHECK(glm::length(l.direction) > 0.f, "lights[", i,
                         "].direction: must be non-zero for a directional light");
        if (l.type == Light::Type::Sphere)
            LUCENT_CHECK(std::isfinite(l.radius) && l.radius > 0.f, "lights[", i,
                         "].radius: must be > 0 mm for a sphere light");
    }
}

std::optional<float> sampleFreeFlight(const GridMedium& medium, const Point3f& o, const Vector3f& d,
                                      float tMax, int ch, Pcg32& rng, TrackingStats* stats) {
    std::optional<float> result;
    const bool homogeneous = medium.isHomogeneous();
    uint64_t lookups = 0;
    medium.forEachMajorantSegment(o, d, 0.f, tMax, ch, [&](float t0, float t1, float majorant) {
        if (!(majorant > 0.f))
            return true;  // empty brick: skipped without a collision
        float t = t0;
        for (;;) {
            t += exponentialStep(rng, majorant);
            if (!(t < t1))
                return true;    // restart in the next segment (memorylessness)
            if (homogeneous) {  // σt = σ̄ everywhere: every collision is real
                result = t;
                return false;
            }
            ++lookups;
            const float st = medium.sigmaT(o + d * t, ch);
            // Accept with probability σt/σ̄ (STAR Eq. 18); otherwise a null collision.
            if (rng.uniform() * majorant < st) {
                result = t;
                return false;
            }
        }
    });
    if (stats) {
        stats->tentativeCollisions += lookups;
        if (result)
            ++stats->realCollisions;
    }
    return result;
}

float estimateTransmittance(const GridMedium& medium, const Point3f& o, const Vector3f& d,
                            float tMax, int ch, Pcg32& rng, TrackingStats* stats) {
    float tr = 1.f;
    const bool homogeneous = medium.isHomogeneous();
    uint64_t lookups = 0;
    medium.forEachMajorantSegment(o, d, 0.f, tMax, ch, [&](float t0, float t1, float majorant) {
        if (!(majorant > 0.f))
            return true;
        if (homogeneous) {  // Beer–Lambert in closed form: T = exp(−σt·ℓ)
            tr *= std::exp(-majorant * (t1 - t0));
            return true;
        }
        float t = t0;
        for (;;) {
            t += exponentialStep(rng, majorant);
            if (!(t < t1))
                return true;
            ++lookups;
            const float st = medium.sigmaT(o + d * t, ch);
            // Ratio tracking: T ×= 1 − σt/σ̄ per tentative collision (Novák 2014, Eq. 7).
            // σt ≤ σ̄ holds by construction; the clamp guards a lookup rounded into a
            // neighbouring brick at a brick face.
            tr *= std::max(0.f, 1.f - st / majorant);
            if (tr < RATIO_ROULETTE) {
                // Unbiased roulette: survive with probability tr/θ, then continue with θ.
                if (tr <= 0.f || rng.uniform() * RATIO_ROULETTE >= tr) {
                    tr = 0.f;
                    return false;
                }
                tr = RATIO_ROULETTE;
            }
        }
    });
    if (stats)
        stats->tentativeCollisions += lookups;
    return tr;
}

WalkResult walkMedium(const VolumeScene& scene, const Point3f& p, const Vector3f& d, int ch,
                      Pcg32& rng, const TransportOptions& options, TrackingStats* stats) {
    WalkResult r;
    const MeshBoundary& boundary = scene.boundary();
    const GridMedium& medium = scene.medium();
    const bool dielectric = options.boundary == BoundaryModel::Dielectric;
    Point3f pos = p;
    Vector3f dir = glm::normalize(d);
    float weight = 1.f;
    int surfaceEvents = 0;
    while (surfaceEvents < MAX_SURFACE_EVENTS) {
        const std::optional<SurfaceHit> exit = boundary.intersect(pos, dir, 0.f, INF);
        if (!exit)
            return r;  // numerically outside the closed mesh: lost
        const std::optional<float> tc = sampleFreeFlight(medium, pos, dir, exit->t, ch, rng, stats);
        if (tc) {
            const Point3f x = pos + dir * *tc;
            const float st = medium.sigmaT(x, ch);
            // Collision weight: single-scattering albedo σs/σt (analog absorption as weight).
            weight *= st > 0.f ? medium.sigmaS(x, ch) / st : 0.f;
            ++r.scatterCount;
            if (!(weight > 0.f) || r.scatterCount > options.maxScatter)
                return r;
            if (options.russianRoulette && !roulette(weight, rng))
                return r;
            dir = sampleHenyeyGreenstein(dir, medium.g(x, ch), {rng.uniform(), rng.uniform()});
            pos = x;
            continue;
        }
        ++surfaceEvents;
        const Point3f x = pos + dir * exit->t;
        const Normal3f n = exit->normal;
        const float off = boundary.offsetAt(x);
        if (dielectric) {
            const float cosO = std::abs(glm::dot(dir, n));
            // Leaving the dense side: relative index 1/η.
            const float f = fresnelDielectric(cosO, 1.f / options.eta);
            if (rng.uniform() < f) {
                dir = glm::normalize(reflect(dir, n));
                pos = x - n * off;
                continue;
            }
            const std::optional<Vector3f> t = refract(dir, -n, 1.f / options.eta);
            if (!t) {  // f = 1 covers TIR; guards rounding at the critical angle
                dir = glm::normalize(reflect(dir, n));
                pos = x - n * off;
                continue;
            }
            dir = *t;
        }
        r.escaped = true;
        r.position = x;
        r.direction = dir;
        r.weight = weight;
        return r;
    }
    return r;
}

float shadowTransmittance(const VolumeScene& scene, const Point3f& p, const Vector3f& wi,
                          float dist, bool pInside, int ch, Pcg32& rng,
                          const TransportOptions& options, TrackingStats* stats) {
    const MeshBoundary& boundary = scene.boundary();
    const bool dielectric = options.boundary == BoundaryModel::Dielectric;
    float tr = 1.f;
    Point3f pos = p;
    float remaining = dist;
    bool inside = pInside;
    for (int crossing = 0; crossing < 256; ++crossing) {
        const std::optional<SurfaceHit> hit = boundary.intersect(pos, wi, 0.f, remaining);
        const float segEnd = hit ? hit->t : remaining;
        if (inside)
            tr *= estimateTransmittance(scene.medium(), pos, wi, segEnd, ch, rng, stats);
        if (!(tr > 0.f) || !hit)
            return tr;
        const Point3f x = pos + wi * hit->t;
        const float off = boundary.offsetAt(x);
        if (dielectric) {
            // Straight shadow connection through the surface, weighted by the Fresnel
            // transmittance 1 − F (refraction of the shadow ray ignored, as the dipole does).
            const float cosT = std::abs(glm::dot(wi, hit->normal));
            tr *= 1.f - fresnelDielectric(cosT, inside ? 1.f / options.eta : options.eta);
        }
        inside = !inside;
        pos = x + wi * off;
        remaining -= hit->t + off;
        if (!(remaining > 0.f))
            return tr;
    }
    return tr;
}

namespace {

/// A camera path at point x of the surface (outward normal n), arriving from outside along
/// `dir`. Moves it across (or off) the surface: updates pos/dir/inside and multiplies `weight`
/// by the deterministic Fresnel split (subsurface-only first event) and the radiance scaling.
/// Returns false when the path ends. Shared by the per-channel and spectral-MIS estimators.
bool enterSurface(const Point3f& x, const Normal3f& n, float off, bool specularChain, Point3f& pos,
                  Vector3f& dir, bool& inside, double& weight, Pcg32& rng,
                  const TransportOptions& options) {
    const float cosI = -glm::dot(dir, n);
    if (cosI < 0.f) {  // reached the surface from inside (camera inside the object)
        inside = true;
        return true;
    }
    if (options.boundary != BoundaryModel::Dielectric) {
        pos = x - n * off;
        inside = true;
        return true;
    }
    const float f = fresnelDielectric(cosI, options.eta);
    if (specularChain && options.subsurfaceOnly) {
        weight *= 1.0 - f;  // deterministic split: keep only the transmitted part
    } else if (rng.uniform() < f) {
        dir = glm::normalize(reflect(dir, n));
        pos = x + n * off;
        return true;
    }
    const std::optional<Vector3f> t = refract(dir, n, options.eta);
    if (!t)
        return false;  // impossible entering a denser medium; rounding guard
    // Radiance is not symmetric under refraction: L_outside = T·L_inside/η²
    // (Veach 1997 §5.2; pbrt-v3 §8.2.3), so a camera path entering the object
    // carries 1/η². The straight shadow connections need no factor: for a point
    // light the refracted fluence equals T·I/d² to first order in depth/d.
    weight /= double(options.eta) * options.eta;
    dir = *t;
    pos = x - n * off;
    inside = true;
    return true;
}

/// A camera path inside the object reaching the surface at x (outward normal n): Fresnel
/// reflection back inside, or refraction out with the inverse radiance scaling η².
void exitSurface(const Point3f& x, const Normal3f& n, float off, Point3f& pos, Vector3f& dir,
                 bool& inside, double& weight, Pcg32& rng, const TransportOptions& options) {
    if (options.boundary == BoundaryModel::Dielectric) {
        const float cosO = std::abs(glm::dot(dir, n));
        const float f = fresnelDielectric(cosO, 1.f / options.eta);
        const std::optional<Vector3f> t =
            rng.uniform() < f ? std::nullopt : refract(dir, -n, 1.f / options.eta);
        if (!t) {
            dir = glm::normalize(reflect(dir, n));
            pos = x - n * off;
            return;
        }
        weight *= double(options.eta) * options.eta;
        dir = *t;
    }
    pos = x + n * off;
    inside = false;
}

}  // namespace

float estimateRadiance(const VolumeScene& scene, const Point3f& o, const Vector3f& d, int ch,
                       Pcg32& rng, const TransportOptions& options, TrackingStats* stats) {
    const MeshBoundary& boundary = scene.boundary();
    const GridMedium& medium = scene.medium();
    float radiance = 0.f;
    float beta = 1.f;
    Point3f pos = o;
    Vector3f dir = glm::normalize(d);
    bool inside = false;
    bool specularChain = true;  // only surface events (no scattering) since the camera
    int scatterCount = 0;
    for (int surfaceEvents = 0; surfaceEvents < MAX_SURFACE_EVENTS;) {
        if (!inside) {
            const std::optional<SurfaceHit> hit = boundary.intersect(pos, dir, 0.f, INF);
            const float tHit = hit ? hit->t : INF;
            // Sphere lights are opaque emitters. Their emission counts only along specular
            // chains; after a scattering event they are reached by next-event estimation.
            float tLight = INF, le = 0.f;
            for (const Light& light : scene.lights()) {
                if (light.type != Light::Type::Sphere)
                    continue;
                const float t = intersectSphere(pos, dir, light.position, light.radius);
                if (t < tLight) {
                    tLight = t;
                    le = light.intensity[ch];
                }
            }
            if (tLight < tHit) {
                if (specularChain)
                    radiance += beta * le;
                break;
            }
            if (!hit)
                break;  // black background
            ++surfaceEvents;
            const Point3f x = pos + dir * tHit;
            const Normal3f n = hit->normal;
            const float off = boundary.offsetAt(x);
            double w = 1.0;
            const bool alive =
                enterSurface(x, n, off, specularChain, pos, dir, inside, w, rng, options);
            beta *= float(w);
            if (!alive)
                break;
            continue;
        }
        const std::optional<SurfaceHit> exit = boundary.intersect(pos, dir, 0.f, INF);
        if (!exit) {
            inside = false;  // numerically outside: continue as an outside ray
            continue;
        }
        const std::optional<float> tc = sampleFreeFlight(medium, pos, dir, exit->t, ch, rng, stats);
        if (tc) {
            const Point3f x = pos + dir * *tc;
            const float st = medium.sigmaT(x, ch);
            beta *= st > 0.f ? medium.sigmaS(x, ch) / st : 0.f;
            if (!(beta > 0.f) || ++scatterCount > options.maxScatter)
                break;
            const float g = medium.g(x, ch);
            radiance += beta * directLighting(scene, x, dir, g, ch, rng, options, stats);
            specularChain = false;
            if (options.russianRoulette && !roulette(beta, rng))
                break;
            dir = sampleHenyeyGreenstein(dir, g, {rng.uniform(), rng.uniform()});
            pos = x;
            continue;
        }
        ++surfaceEvents;
        const Point3f x = pos + dir * exit->t;
        const Normal3f n = exit->normal;
        const float off = boundary.offsetAt(x);
        double w = 1.0;
        exitSurface(x, n, off, pos, dir, inside, w, rng, options);
        beta *= float(w);
    }
    return std::isfinite(radiance) ? radiance : 0.f;
}

// ---------------------------------------------------------------------------------------------
// Spectral MIS (hero channel) estimators.
//
// Null-scattering path formulation (Miller, Georgiev & Jarosz 2019, Eq. 9–12): with a common
// majorant σ̄ ≥ σt,c for every channel c, a tentative collision is real with probability
// σt,c/σ̄ or null with probability σn,c/σ̄, σn = σ̄ − σt, under technique c; the throughput of
// channel c gains σs,c·p_c(θ) at a real scattering event and σn,c at a null one, its pdf under
// technique k gains σt,k·p_k(θ) and σn,k (the exponential factors are shared and cancel).
// The one-sample balance heuristic over the three techniques (Veach 1997, Eq. 9.15) gives the
// channel-c estimate f_c / ((1/3) Σ_k p_k). We keep w_c = f_c / p_hero and q_k = p_k / p_hero
// in double precision, renormalised after every event so that mean(q) = 1 (only the ratio
// matters), so the estimate of the path prefix is simply w_c.
// ---------------------------------------------------------------------------------------------

namespace {

/// MIS state of a path prefix: contribution ratios w (per channel) and pdf ratios q.
struct SpectralWeights {
    double w[3] = {1, 1, 1};
    double q[3] = {1, 1, 1};

    /// Multiplies channel c's throughput by f[c] and technique k's pdf by p[k], with the hero's
    /// pdf factor p[hero] > 0 divided out; then renormalises mean(q) to 1.
    void update(const double f[3], const double p[3], int hero) {
        const double ph = p[hero];
        for (int c = 0; c < 3; ++c) {
            w[c] *= f[c] / ph;
            q[c] *= p[c] / ph;
        }
        const double mean = (q[0] + q[1] + q[2]) / 3.0;
        for (int c = 0; c < 3; ++c) {
            w[c] /= mean;
            q[c] /= mean;
        }
    }
    [[nodiscard]] double maxWeight() const { return std::max({w[0], w[1], w[2]}); }
    [[nodiscard]] bool isZero() const { return !(maxWeight() > 0.0); }
};

/// Delta tracking with the hero channel against the common majorant; updates the MIS weights
/// at every null and real collision. Returns the real collision's distance, if any.
std::optional<float> sampleFreeFlightMis(const GridMedium& medium, const Point3f& o,
                                         const Vector3f& d, float tMax, int hero, Pcg32& rng,
                                         SpectralWeights& sw, TrackingStats* stats) {
    std::optional<float> result;
    uint64_t lookups = 0;
    medium.forEachMajorantSegment(
        o, d, 0.f, tMax, GridMedium::ANY_CHANNEL, [&](float t0, float t1, float majorant) {
            if (!(majorant > 0.f))
                return true;
            float t = t0;
            for (;;) {
                t += exponentialStep(rng, majorant);
                if (!(t < t1))
                    return true;
                ++lookups;
                const int64_t v = medium.voxelIndex(o + d * t);
                double st[3];
                for (int c = 0; c < 3; ++c)
                    st[c] = v < 0 ? 0.0 : std::min(double(medium.sigmaTAt(v, c)), double(majorant));
                // Real collision (the hero decides); st ≥ σ̄ (rounding) counts as real so that
                // the hero's null probability is never zero.
                if (st[hero] >= double(majorant) || rng.uniform() * majorant < st[hero]) {
                    double f[3];
                    for (int c = 0; c < 3; ++c)
                        f[c] = double(medium.sigmaSAt(v, c));
                    sw.update(f, st, hero);  // throughput σs,c; pdf σt,k (σ̄ cancels)
                    result = t;
                    return false;
                }
                double sn[3];
                for (int c = 0; c < 3; ++c)
                    sn[c] = double(majorant) - st[c];
                sw.update(sn, sn, hero);  // null collision: σn in throughput and pdf
            }
        });
    if (stats) {
        stats->tentativeCollisions += lookups;
        if (result)
            ++stats->realCollisions;
    }
    return result;
}

Rgb shadowTransmittanceRgb(const VolumeScene& scene, const Point3f& p, const Vector3f& wi,
                           float dist, int hero, Pcg32& rng, const TransportOptions& options,
                           TrackingStats* stats) {
    const MeshBoundary& boundary = scene.boundary();
    const bool dielectric = options.boundary == BoundaryModel::Dielectric;
    Rgb tr(1.f);
    Point3f pos = p;
    float remaining = dist;
    bool inside = true;
    for (int crossing = 0; crossing < 256; ++crossing) {
        const std::optional<SurfaceHit> hit = boundary.intersect(pos, wi, 0.f, remaining);
        const float segEnd = hit ? hit->t : remaining;
        if (inside)
            tr *= estimateTransmittanceRgb(scene.medium(), pos, wi, segEnd, rng, stats);
        if (!(std::max({tr.r, tr.g, tr.b}) > 0.f) || !hit)
            return tr;
        const Point3f x = pos + wi * hit->t;
        const float off = boundary.offsetAt(x);
        if (dielectric) {  // straight connection weighted by 1 − F (as in shadowTransmittance)
            const float cosT = std::abs(glm::dot(wi, hit->normal));
            tr *= 1.f - fresnelDielectric(cosT, inside ? 1.f / options.eta : options.eta);
        }
        inside = !inside;
        pos = x + wi * off;
        remaining -= hit->t + off;
        if (!(remaining > 0.f))
            return tr;
    }
    (void)hero;
    return tr;
}

/// NEE for all channels at a real collision (see directLighting), phase per channel.
Rgb directLightingRgb(const VolumeScene& scene, const Point3f& x, const Vector3f& dirIn,
                      const Rgb& g, int hero, Pcg32& rng, const TransportOptions& options,
                      TrackingStats* stats) {
    Rgb sum(0.f);
    for (const Light& light : scene.lights()) {
        const std::optional<LightSample> ls = sampleLightFrom(light, x, rng);
        if (!ls)
            continue;
        const Vector3f wi = ls->wi;
        const float dist = ls->dist;
        const Rgb le = ls->le;
        if (!(std::max({le.r, le.g, le.b}) > 0.f))
            continue;
        const float cosT = glm::dot(dirIn, wi);
        const Rgb phase(hgPhase(g.r, cosT), hgPhase(g.g, cosT), hgPhase(g.b, cosT));
        const Rgb tr = shadowTransmittanceRgb(scene, x, wi, dist, hero, rng, options, stats);
        sum += phase * tr * le;
    }
    return sum;
}

Rgb toRgb(const SpectralWeights& sw) {
    return Rgb(float(sw.w[0]), float(sw.w[1]), float(sw.w[2]));
}

}  // namespace

Rgb estimateTransmittanceRgb(const GridMedium& medium, const Point3f& o, const Vector3f& d,
                             float tMax, Pcg32& rng, TrackingStats* stats) {
    Rgb tr(1.f);
    uint64_t lookups = 0;
    medium.forEachMajorantSegment(
        o, d, 0.f, tMax, GridMedium::ANY_CHANNEL, [&](float t0, float t1, float majorant) {
            if (!(majorant > 0.f))
                return true;
            float t = t0;
            for (;;) {
                t += exponentialStep(rng, majorant);
                if (!(t < t1))
                    return true;
                ++lookups;
                const int64_t v = medium.voxelIndex(o + d * t);
                if (v < 0)
                    continue;  // σt = 0 outside the grid: factor 1
                // Ratio tracking per channel against the common majorant (Novák 2014, Eq. 7).
                for (int c = 0; c < 3; ++c)
                    tr[c] *= std::max(0.f, 1.f - medium.sigmaTAt(v, c) / majorant);
                const float m = std::max({tr.r, tr.g, tr.b});
                if (m < RATIO_ROULETTE) {  // roulette on the largest channel, unbiased
                    if (m <= 0.f || rng.uniform() * RATIO_ROULETTE >= m) {
                        tr = Rgb(0.f);
                        return false;
                    }
                    tr *= RATIO_ROULETTE / m;
                }
            }
        });
    if (stats)
        stats->tentativeCollisions += lookups;
    return tr;
}

Rgb estimateRadianceRgb(const VolumeScene& scene, const Point3f& o, const Vector3f& d, int hero,
                        Pcg32& rng, const TransportOptions& options, TrackingStats* stats) {
    const MeshBoundary& boundary = scene.boundary();
    const GridMedium& medium = scene.medium();
    hero = std::clamp(hero, 0, 2);
    Rgb radiance(0.f);
    SpectralWeights sw;
    double scale = 1.0;  // Fresnel split and roulette factors (common to all channels)
    Point3f pos = o;
    Vector3f dir = glm::normalize(d);
    bool inside = false;
    bool specularChain = true;
    int scatterCount = 0;
    for (int surfaceEvents = 0; surfaceEvents < MAX_SURFACE_EVENTS;) {
        if (!inside) {
            const std::optional<SurfaceHit> hit = boundary.intersect(pos, dir, 0.f, INF);
            const float tHit = hit ? hit->t : INF;
            float tLight = INF;
            Rgb le(0.f);
            for (const Light& light : scene.lights()) {
                if (light.type != Light::Type::Sphere)
                    continue;
                const float t = intersectSphere(pos, dir, light.position, light.radius);
                if (t < tLight) {
                    tLight = t;
                    le = light.intensity;
                }
            }
            if (tLight < tHit) {
                if (specularChain)
                    radiance += float(scale) * toRgb(sw) * le;
                break;
            }
            if (!hit)
                break;
            ++surfaceEvents;
            const Point3f x = pos + dir * tHit;
            const Normal3f n = hit->normal;
            const float off = boundary.offsetAt(x);
            if (!enterSurface(x, n, off, specularChain, pos, dir, inside, scale, rng, options))
                break;
            continue;
        }
        const std::optional<SurfaceHit> exit = boundary.intersect(pos, dir, 0.f, INF);
        if (!exit) {
            inside = false;
            continue;
        }
        const std::optional<float> tc =
            sampleFreeFlightMis(medium, pos, dir, exit->t, hero, rng, sw, stats);
        if (sw.isZero())
            break;
        if (tc) {
            const Point3f x = pos + dir * *tc;
            if (++scatterCount > options.maxScatter)
                break;
            const Rgb g(medium.g(x, 0), medium.g(x, 1), medium.g(x, 2));
            radiance += float(scale) * toRgb(sw) *
                        directLightingRgb(scene, x, dir, g, hero, rng, options, stats);
            specularChain = false;
            // Roulette on the largest channel weight (unbiased: survivors divided by q).
            const double m = scale * sw.maxWeight();
            if (options.russianRoulette && m < ROULETTE_WEIGHT) {
                const double q = m / ROULETTE_WEIGHT;
                if (rng.uniform() >= q)
                    break;
                scale /= q;
            }
            const Vector3f next =
                sampleHenyeyGreenstein(dir, g[hero], {rng.uniform(), rng.uniform()});
            const float cosT = glm::dot(dir, next);
            double p[3];
            for (int c = 0; c < 3; ++c)
                p[c] = double(hgPhase(g[c], cosT));
            sw.update(p, p, hero);  // phase value in throughput and pdf alike
            dir = next;
            pos = x;
            continue;
        }
        ++surfaceEvents;
        const Point3f x = pos + dir * exit->t;
        const Normal3f n = exit->normal;
        const float off = boundary.offsetAt(x);
        exitSurface(x, n, off, pos, dir, inside, scale, rng, options);
    }
    return isFinite(radiance) ? radiance : Rgb(0.f);
}

}  // namespace lucent
