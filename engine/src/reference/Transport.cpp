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
/// Eq. 8.1–8.2. Hero-channel spectral MIS: Miller, Georgiev & Jarosz 2019, Eq. 9–12; Veach
/// 1997, Eq. 9.15; Wilkie et al. 2014.
///
/// Structure: every tracker (delta tracking, ratio tracking, shadow rays, next-event
/// estimation, the camera path) is implemented once, as a template over a channel policy
/// (OneChannel / ChannelPath for per-channel tracking, AllChannels / HeroPath for spectral MIS);
/// the public functions at the end instantiate them.

#include <lucent/core/Error.h>
#include <lucent/core/Fresnel.h>
#include <lucent/core/Sampling.h>
#include <lucent/core/SphericalHarmonics.h>
#include <lucent/reference/SpecularChain.h>
#include <lucent/reference/Transport.h>

namespace lucent::reference {

namespace {

/// Surface interactions without a scattering event after which a path is dropped (a ray
/// trapped by total internal reflection in a vacuum pocket; never reached in practice).
constexpr int MAX_SURFACE_EVENTS = 1 << 16;
/// Weight-window Russian roulette threshold (unbiased: survivors get weight / q).
constexpr float ROULETTE_WEIGHT = 0.5f;
/// Ratio-tracking roulette threshold on the running transmittance.
constexpr float RATIO_ROULETTE = 0.1f;
/// Refracted next-event estimation runs every time within this many mean free paths (σt at the
/// scattering point) of the surface towards the light, and with probability e^{−(τ − this)}
/// beyond (Russian roulette, unbiased; refractedLighting).
constexpr float NEE_FULL_DEPTH = 2.f;
/// ... but never with probability below this.
constexpr float NEE_MIN_Q = 1.f / 256.f;
/// The trials that estimate a chain's reciprocal probability run every time for a chain that
/// carries at least this share of the light at x, and proportionally less often below it.
constexpr float CHAIN_SHARE = 0.01f;
/// A guard against an endless trial loop (a chain that a seed can no longer reach because of
/// rounding); never reached in the tests and benchmarks.
constexpr uint64_t MAX_CHAIN_TRIALS = uint64_t(1) << 24;

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

}  // namespace

const char* boundaryModelName(BoundaryModel model) {
    switch (model) {
        case BoundaryModel::Matched:
            return "matched";
        case BoundaryModel::Dielectric:
            return "dielectric";
        case BoundaryModel::Straight:
            return "straight";
    }
    return "?";
}

BoundaryModel parseBoundaryModel(const std::string& name) {
    for (BoundaryModel m :
         {BoundaryModel::Dielectric, BoundaryModel::Matched, BoundaryModel::Straight})
        if (name == boundaryModelName(m))
            return m;
    LUCENT_THROW(ValueError,
                 "boundary: expected 'dielectric' (exact, the default), 'matched' (η = 1) or "
                 "'straight' (fast approximation, not ground truth), got '",
                 name, "'");
}

VolumeScene::VolumeScene(const TriangleMesh& mesh, GridMedium medium, std::vector<Light> lights,
                         const Rgb& environment)
    : m_boundary(mesh),
      m_refractions(mesh),
      m_medium(std::move(medium)),
      m_lights(std::move(lights)),
      m_environment(environment) {
    LUCENT_CHECK(isFinite(environment) && environment.r >= 0.f && environment.g >= 0.f &&
                     environment.b >= 0.f,
                 "environment radiance must be finite and ≥ 0 W/(mm²·sr)");
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

namespace {

/// A camera path at point x of the surface (outward normal n), arriving from outside along
/// `dir`. Moves it across (or off) the surface: updates pos/dir/inside and multiplies `weight`
/// by the deterministic Fresnel split (subsurface-only first event) and the radiance scaling.
/// Returns false when the path ends.
bool enterSurface(const Point3f& x, const Normal3f& n, float off, bool specularChain, Point3f& pos,
                  Vector3f& dir, bool& inside, double& weight, Pcg32& rng,
                  const TransportOptions& options) {
    const float cosI = -glm::dot(dir, n);
    if (cosI < 0.f) {  // reached the surface from inside (camera inside the object)
        inside = true;
        return true;
    }
    if (options.boundary == BoundaryModel::Matched) {
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
    // carries 1/η². Next-event estimation needs no factor: it carries irradiance,
    // and flux is conserved through the surface (RefractionSearch.h).
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
    if (options.boundary != BoundaryModel::Matched) {
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

// ---------------------------------------------------------------------------------------------
// Channel policies.
//
// Each estimator below is written once, as a template over a channel policy that holds only
// what differs between the two colour modes of docs/reference.md:
//  * OneChannel / ChannelPath: per-channel tracking, one channel `ch` as a scalar path tracer
//    against its own majorant (with the homogeneous closed form where the medium allows it);
//  * AllChannels / HeroPath: all three channels against the common majorant
//    (GridMedium::ANY_CHANNEL), free flights sampled with the hero channel and weighted by
//    hero-channel spectral MIS (the SpectralWeights below).
// The policies keep each mode's arithmetic and random-number consumption exactly, so both modes
// give the same bits as their former separate implementations (docs/reference.md).
//
// Spectral MIS (hero channel). Null-scattering path formulation (Miller, Georgiev & Jarosz
// 2019, Eq. 9–12): with a common majorant σ̄ ≥ σt,c for every channel c, a tentative collision is
// real with probability σt,c/σ̄ or null with probability σn,c/σ̄, σn = σ̄ − σt, under technique
// c; the throughput of channel c gains σs,c·p_c(θ) at a real scattering event and σn,c at a null
// one, its pdf under technique k gains σt,k·p_k(θ) and σn,k (the exponential factors are shared
// and cancel). The one-sample balance heuristic over the three techniques (Veach 1997,
// Eq. 9.15) gives the channel-c estimate f_c / ((1/3) Σ_k p_k). We keep w_c = f_c / p_hero and
// q_k = p_k / p_hero in double precision, renormalised after every event so that mean(q) = 1
// (only the ratio matters), so the estimate of the path prefix is simply w_c.
// ---------------------------------------------------------------------------------------------

bool allFinite(float v) {
    return std::isfinite(v);
}
bool allFinite(const Rgb& v) {
    return isFinite(v);
}

/// The trackers' view of one colour channel `ch`: its own majorant, a scalar transmittance.
struct OneChannel {
    using Value = float;
    int ch = 0;

    [[nodiscard]] int majorantChannel() const { return ch; }
    /// Homogeneous medium: σ̄ = σt everywhere, so flights and transmittance are exponential.
    [[nodiscard]] static bool closedForm(const GridMedium& medium) {
        return medium.isHomogeneous();
    }
    [[nodiscard]] static float largest(float v) { return v; }
    /// This channel's part of an RGB quantity.
    [[nodiscard]] float pick(const Rgb& v) const { return v[ch]; }
    /// Ratio-tracking factor at voxel v ≥ 0: T ×= 1 − σt/σ̄ (Novák 2014, Eq. 7). σt ≤ σ̄ holds
    /// by construction; the clamp guards a lookup rounded into a neighbouring brick at a brick
    /// face.
    void attenuate(float& tr, const GridMedium& medium, int64_t v, float majorant) const {
        tr *= std::max(0.f, 1.f - medium.sigmaTAt(v, ch) / majorant);
    }
    /// Survivor of the ratio-tracking roulette (probability tr/θ) continues with θ.
    static void survive(float& tr, float /*largest*/) { tr = RATIO_ROULETTE; }
    /// Delta tracking at voxel v (−1: outside the grid): a real collision with probability
    /// σt/σ̄ (STAR Eq. 18), otherwise a null collision.
    bool collide(const GridMedium& medium, int64_t v, float majorant, Pcg32& rng) const {
        const float st = v < 0 ? 0.f : medium.sigmaTAt(v, ch);
        return rng.uniform() * majorant < st;
    }
};

/// The trackers' view of all three channels against the common majorant (Rgb transmittance).
struct AllChannels {
    using Value = Rgb;

    [[nodiscard]] static int majorantChannel() { return GridMedium::ANY_CHANNEL; }
    /// Never: the common σ̄ equals σt in one channel at most.
    [[nodiscard]] static bool closedForm(const GridMedium& /*medium*/) { return false; }
    [[nodiscard]] static float largest(const Rgb& v) { return std::max({v.r, v.g, v.b}); }
    [[nodiscard]] static const Rgb& pick(const Rgb& v) { return v; }
    /// Ratio tracking per channel against the common majorant (Novák 2014, Eq. 7).
    static void attenuate(Rgb& tr, const GridMedium& medium, int64_t v, float majorant) {
        for (int c = 0; c < 3; ++c)
            tr[c] *= std::max(0.f, 1.f - medium.sigmaTAt(v, c) / majorant);
    }
    /// Roulette on the largest channel (survival probability largest/θ): rescale all channels.
    static void survive(Rgb& tr, float largest) { tr *= RATIO_ROULETTE / largest; }
};

/// A per-channel camera path: scalar throughput β of channel `ch`.
struct ChannelPath : OneChannel {
    using Tracker = OneChannel;
    float beta = 1.f;

    [[nodiscard]] float throughput() const { return beta; }
    /// False: the scalar weight does not change during a free flight (only at the collision,
    /// where scatterAlbedo checks it).
    [[nodiscard]] static bool isBlack() { return false; }
    /// Surface crossing: `cross(w)` multiplies a fresh weight w (Fresnel split, radiance
    /// scaling), folded into β; returns whether the path goes on.
    template <typename F>
    bool crossSurface(F&& cross) {
        double w = 1.0;
        const bool alive = cross(w);
        beta *= float(w);
        return alive;
    }
    /// Real collision at x: β ×= single-scattering albedo σs/σt. Returns false if β is zero.
    bool scatterAlbedo(const GridMedium& medium, const Point3f& x) {
        const float st = medium.sigmaT(x, ch);
        beta *= st > 0.f ? medium.sigmaS(x, ch) / st : 0.f;
        return beta > 0.f;
    }
    [[nodiscard]] float g(const GridMedium& medium, const Point3f& x) const {
        return medium.g(x, ch);
    }
    [[nodiscard]] static float phase(float g, float cosT) { return hgPhase(g, cosT); }
    /// Weight-window roulette on β (unbiased: survivors get weight / q). False: terminated.
    bool roulette(Pcg32& rng) {
        if (beta >= ROULETTE_WEIGHT)
            return true;
        const float q = beta / ROULETTE_WEIGHT;
        if (rng.uniform() >= q)
            return false;
        beta = ROULETTE_WEIGHT;
        return true;
    }
    /// New travel direction drawn from HG with this channel's g.
    static Vector3f scatter(const Vector3f& dir, float g, Pcg32& rng) {
        return sampleHenyeyGreenstein(dir, g, {rng.uniform(), rng.uniform()});
    }
};

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

/// A hero-channel spectral-MIS camera path: MIS weights of all three channels, sampled with
/// channel `hero`'s coefficients.
struct HeroPath : AllChannels {
    using Tracker = AllChannels;
    int hero = 0;
    SpectralWeights weights;
    double scale = 1.0;  ///< Fresnel split and roulette factors (common to all channels)

    [[nodiscard]] Rgb throughput() const {
        return float(scale) * Rgb(float(weights.w[0]), float(weights.w[1]), float(weights.w[2]));
    }
    /// True when null collisions zeroed every channel's weight.
    [[nodiscard]] bool isBlack() const { return weights.isZero(); }
    template <typename F>
    bool crossSurface(F&& cross) {
        return cross(scale);
    }
    /// Delta tracking with the hero channel against the common majorant, updating the MIS
    /// weights at every null and real collision.
    bool collide(const GridMedium& medium, int64_t v, float majorant, Pcg32& rng) {
        double st[3];
        for (int c = 0; c < 3; ++c)
            st[c] = v < 0 ? 0.0 : std::min(double(medium.sigmaTAt(v, c)), double(majorant));
        // Real collision (the hero decides); st ≥ σ̄ (rounding) counts as real so that the
        // hero's null probability is never zero.
        if (st[hero] >= double(majorant) || rng.uniform() * majorant < st[hero]) {
            double f[3];
            for (int c = 0; c < 3; ++c)
                f[c] = double(medium.sigmaSAt(v, c));
            weights.update(f, st, hero);  // throughput σs,c; pdf σt,k (σ̄ cancels)
            return true;
        }
        double sn[3];
        for (int c = 0; c < 3; ++c)
            sn[c] = double(majorant) - st[c];
        weights.update(sn, sn, hero);  // null collision: σn in throughput and pdf
        return false;
    }
    /// True: σs,c already entered the weights at the collision (collide).
    static bool scatterAlbedo(const GridMedium& /*medium*/, const Point3f& /*x*/) { return true; }
    [[nodiscard]] static Rgb g(const GridMedium& medium, const Point3f& x) {
        return {medium.g(x, 0), medium.g(x, 1), medium.g(x, 2)};
    }
    [[nodiscard]] static Rgb phase(const Rgb& g, float cosT) {
        return {hgPhase(g.r, cosT), hgPhase(g.g, cosT), hgPhase(g.b, cosT)};
    }
    /// Roulette on the largest channel weight (unbiased: survivors divided by q).
    bool roulette(Pcg32& rng) {
        const double m = scale * weights.maxWeight();
        if (m >= ROULETTE_WEIGHT)
            return true;
        const double q = m / ROULETTE_WEIGHT;
        if (rng.uniform() >= q)
            return false;
        scale /= q;
        return true;
    }
    /// New direction drawn from HG with g_hero; the phase values of every channel enter the
    /// throughput and the pdf alike.
    Vector3f scatter(const Vector3f& dir, const Rgb& g, Pcg32& rng) {
        const Vector3f next = sampleHenyeyGreenstein(dir, g[hero], {rng.uniform(), rng.uniform()});
        const float cosT = glm::dot(dir, next);
        double p[3];
        for (int c = 0; c < 3; ++c)
            p[c] = double(hgPhase(g[c], cosT));
        weights.update(p, p, hero);
        return next;
    }
};

// ---------------------------------------------------------------------------------------------
// Trackers, one implementation each.
// ---------------------------------------------------------------------------------------------

/// Delta (Woodcock) tracking along o + t·d, t ∈ [0, tMax]: the first real collision decided
/// by `channels.collide` (STAR Sec. 4.1), restarting the exponential step at every majorant
/// segment (memorylessness). The segment callback is forced inline: as a call from the
/// majorant walk it cost the spectral-MIS estimator ≈ 0.4 % more instructions (callgrind,
/// docs/benchmarks.md).
template <typename Channels>
std::optional<float> trackFreeFlight(const GridMedium& medium, const Point3f& o, const Vector3f& d,
                                     float tMax, Channels& channels, Pcg32& rng,
                                     TrackingStats* stats) {
    std::optional<float> result;
    const bool closedForm = channels.closedForm(medium);
    uint64_t lookups = 0;
    medium.forEachMajorantSegment(
        o, d, 0.f, tMax, channels.majorantChannel(),
        [&](float t0, float t1, float majorant) __attribute__((always_inline)) {
            if (!(majorant > 0.f))
                return true;  // empty brick: skipped without a collision
            float t = t0;
            for (;;) {
                t += exponentialStep(rng, majorant);
                if (!(t < t1))
                    return true;   // restart in the next segment (memorylessness)
                if (closedForm) {  // σt = σ̄ everywhere: every collision is real
                    result = t;
                    return false;
                }
                ++lookups;
                if (channels.collide(medium, medium.voxelIndex(o + d * t), majorant, rng)) {
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

/// Ratio tracking (Novák 2014, Sec. 3) of exp(−∫₀^tMax σt) along o + t·d, with unbiased
/// roulette once the (largest) transmittance falls below RATIO_ROULETTE.
template <typename Channels>
typename Channels::Value trackTransmittance(const GridMedium& medium, const Point3f& o,
                                            const Vector3f& d, float tMax, const Channels& channels,
                                            Pcg32& rng, TrackingStats* stats) {
    using Value = typename Channels::Value;
    Value tr(1.f);
    const bool closedForm = channels.closedForm(medium);
    uint64_t lookups = 0;
    medium.forEachMajorantSegment(
        o, d, 0.f, tMax, channels.majorantChannel(), [&](float t0, float t1, float majorant) {
            if (!(majorant > 0.f))
                return true;
            if (closedForm) {  // Beer–Lambert in closed form: T = exp(−σt·ℓ)
                tr *= std::exp(-majorant * (t1 - t0));
                return true;
            }
            float t = t0;
            for (;;) {
                t += exponentialStep(rng, majorant);
                if (!(t < t1))
                    return true;
                ++lookups;
                const int64_t v = medium.voxelIndex(o + d * t);
                if (v < 0)
                    continue;  // σt = 0 outside the grid: factor 1
                channels.attenuate(tr, medium, v, majorant);
                const float m = channels.largest(tr);
                if (m < RATIO_ROULETTE) {
                    // Unbiased roulette: survive with probability m/θ, then continue with θ.
                    if (m <= 0.f || rng.uniform() * RATIO_ROULETTE >= m) {
                        tr = Value(0.f);
                        return false;
                    }
                    channels.survive(tr, m);
                }
            }
        });
    if (stats)
        stats->tentativeCollisions += lookups;
    return tr;
}

/// Transmittance of a shadow ray (see shadowTransmittance in Transport.h).
template <typename Channels>
typename Channels::Value traceShadowRay(const VolumeScene& scene, const Point3f& p,
                                        const Vector3f& wi, float dist, bool pInside,
                                        const Channels& channels, Pcg32& rng,
                                        const TransportOptions& options, TrackingStats* stats) {
    using Value = typename Channels::Value;
    const MeshBoundary& boundary = scene.boundary();
    const bool dielectric = options.boundary != BoundaryModel::Matched;
    Value tr(1.f);
    Point3f pos = p;
    float remaining = dist;
    bool inside = pInside;
    for (int crossing = 0; crossing < 256; ++crossing) {
        const std::optional<SurfaceHit> hit = boundary.intersect(pos, wi, 0.f, remaining);
        const float segEnd = hit ? hit->t : remaining;
        if (inside)
            tr *= trackTransmittance(scene.medium(), pos, wi, segEnd, channels, rng, stats);
        if (!(channels.largest(tr) > 0.f) || !hit)
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

/// True when the segment o + t·d, t ∈ (0, tMax), meets a sphere light other than `except`
/// (sphere lights are opaque emitters, for shadow rays as for camera rays).
bool blockedBySphereLight(const VolumeScene& scene, const Point3f& o, const Vector3f& d, float tMax,
                          const Light* except) {
    for (const Light& light : scene.lights())
        if (light.type == Light::Type::Sphere && &light != except &&
            intersectSphere(o, d, light.position, light.radius) < tMax)
            return true;
    return false;
}

/// True when next-event estimation connects through RefractionSearch (the exact dielectric
/// boundary); otherwise shadow rays go straight (exact for the matched boundary, and for a
/// dielectric of η = 1, which refracts nothing).
bool refractedNextEvent(const TransportOptions& options) {
    return options.boundary == BoundaryModel::Dielectric && options.eta != 1.f;
}

/// A direction drawn uniformly on the unit sphere (pdf 1/4π).
Vector3f uniformSphereDirection(Pcg32& rng) {
    return sampleUniformSphere({rng.uniform(), rng.uniform()});
}

/// Next-event estimation with straight shadow rays from a real collision at x (inside the
/// object): Σ over lights of phase · transmittance · radiance / pdf, plus the environment
/// (one direction drawn uniformly). `dirIn` is the path's travel direction at x. Exact for the
/// matched boundary; the Straight approximation with Fresnel factors otherwise.
template <typename Path>
typename Path::Value straightLighting(const VolumeScene& scene, const Point3f& x,
                                      const Vector3f& dirIn, const typename Path::Value& g,
                                      const Path& path, Pcg32& rng, const TransportOptions& options,
                                      TrackingStats* stats) {
    using Value = typename Path::Value;
    const auto& tracker = static_cast<const typename Path::Tracker&>(path);
    Value sum(0.f);
    const auto connect = [&](const Vector3f& wi, float dist, const Rgb& radianceOverPdf,
                             const Light* source) {
        const Value le = path.pick(radianceOverPdf);
        if (!(path.largest(le) > 0.f))
            return;
        // HG phase value for the angle between the path's travel direction and wi (the
        // light's travel direction −wi against −dirIn gives the same cosine).
        const Value phase = path.phase(g, glm::dot(dirIn, wi));
        if (!(path.largest(phase) > 0.f))
            return;  // hgPhase > 0 unless rounding of 1 + g² − 2g·cos bites (|g| ≳ 0.9995)
        if (blockedBySphereLight(scene, x, wi, dist, source))
            return;
        const Value tr =
            traceShadowRay(scene, x, wi, dist, /*pInside=*/true, tracker, rng, options, stats);
        sum += phase * tr * le;
    };
    for (const Light& light : scene.lights())
        if (const std::optional<LightSample> ls = sampleLightFrom(light, x, rng))
            connect(ls->wi, ls->dist, ls->le, &light);
    if (scene.environment() != Rgb(0.f))
        connect(uniformSphereDirection(rng), INF, scene.environment() * (4.f * PI), nullptr);
    return sum;
}

/// The light a point, spot, directional or sphere light sends to x along a specular chain, times
/// the phase function toward the path: strength · Fresnel product · irradiance gain · medium
/// transmittance of every inside segment · phase. Other sphere lights occlude the outside
/// segments.
template <typename Path>
typename Path::Value chainContribution(const VolumeScene& scene, const Point3f& x,
                                       const Vector3f& dirIn, const typename Path::Value& g,
                                       const Path& path, const SpecularChain& chain,
                                       const Light& light, Pcg32& rng, TrackingStats* stats) {
    using Value = typename Path::Value;
    // Directional: irradiance; point, spot: intensity toward the chain; sphere: radiance (the
    // caller multiplies by cos θy·dA/pdf).
    const Rgb strength = light.type == Light::Type::Point || light.type == Light::Type::Spot
                             ? light.intensityToward(-chain.finalDirection)
                             : light.intensity;
    Value value = path.pick(strength) * float(chain.fresnel * chain.irradianceGain) *
                  path.phase(g, glm::dot(dirIn, chain.directionAtX));
    if (!(path.largest(value) > 0.f))
        return Value(0.f);
    const auto& tracker = static_cast<const typename Path::Tracker&>(path);
    Point3f from = x;
    for (int i = 0; i < chain.events; ++i) {
        const Point3f to = chain.points[size_t(i)];
        const Vector3f d = to - from;
        const float len = glm::length(d);
        if (len > 0.f) {
            if (chain.insideBefore[size_t(i)])
                value *=
                    trackTransmittance(scene.medium(), from, d / len, len, tracker, rng, stats);
            else if (blockedBySphereLight(scene, from, d / len, len, nullptr))
                return Value(0.f);
        }
        from = to;
    }
    if (blockedBySphereLight(scene, from, chain.finalDirection, chain.distanceToSource, &light))
        return Value(0.f);
    return value;
}

/// Next-event estimation through the exact dielectric boundary from a real collision at x
/// (docs/reference.md, "Refracted next-event estimation" and "Chains of surface events"), for
/// every light (a point drawn on a sphere light, a direction of the environment):
///  * the light that reaches x through one refraction: every refraction point p that
///    RefractionSearch finds, with the visibility of x → p and p → light, the medium's
///    transmittance along x → p, the Fresnel transmittance and the refracted pencil's gain;
///  * the light of point, spot, directional and sphere lights that reaches x through more
///    surface events (internal reflections, other parts of a non-convex object): specular
///    chains. A random seed gives a chain type, Newton's method the exact chain; the
///    probability that the seed process finds this chain is unknown, so its reciprocal is
///    estimated without bias by the number K of independent trials until the process finds
///    it again (Zeltner, Georgiev & Jakob 2020, Sec. 4.3).
/// The environment's longer chains are found by the camera path itself (tracePath).
/// Russian roulettes (unbiased: kept with probability q, weighted 1/q) spend the work where
/// light arrives: light reaching x crosses at least the straight distance d to the surface
/// towards the source, so its transmittance is about exp(−σt(x)·d); q = 1 within
/// NEE_FULL_DEPTH mean free paths, then falling as that transmittance, never below NEE_MIN_Q.
/// A chain's trials also run only with a probability that follows its share of the light.
template <typename Path>
typename Path::Value refractedLighting(const VolumeScene& scene, const Point3f& x,
                                       const Vector3f& dirIn, const typename Path::Value& g,
                                       const Path& path, Pcg32& rng,
                                       const TransportOptions& options, TrackingStats* stats) {
    using Value = typename Path::Value;
    const MeshBoundary& boundary = scene.boundary();
    const RefractionSearch& search = scene.refractions();
    const SpecularChainTracer chains(boundary, options.eta);
    const auto& tracker = static_cast<const typename Path::Tracker&>(path);
    const float eta = options.eta;
    float sigmaMin = INF;
    for (int c = 0; c < 3; ++c)
        sigmaMin = std::min(sigmaMin, scene.medium().sigmaT(x, c));
    const auto keepProbability = [&](float distance) {
        const float tau = sigmaMin * distance - NEE_FULL_DEPTH;
        return tau <= 0.f ? 1.f : std::max(NEE_MIN_Q, std::exp(-tau));
    };

    // One refraction light → p → x; `strength`: intensity toward p (W/sr) or irradiance
    // (W/mm²) per channel, times the estimator's weight.
    Value refracted(0.f);
    const auto connect = [&](const Refraction& r, const Rgb& strength, const Light* source) {
        const Value le = path.pick(strength);
        if (!(path.largest(le) > 0.f))
            return;
        const Vector3f wi = -r.transmitted;  // from x towards p
        const Value phase = path.phase(g, glm::dot(dirIn, wi));
        if (!(path.largest(phase) > 0.f))
            return;
        const float off = boundary.offsetAt(r.p);
        if (r.distInside > 2.f * off && boundary.occluded(x, wi, 0.f, r.distInside - off))
            return;  // another face between x and p: the path would have left the medium
        const Point3f outside = r.p + r.normal * off;
        const float reach = std::isfinite(r.distOutside) ? r.distOutside - off : INF;
        if (boundary.occluded(outside, -r.incident, 0.f, reach) ||
            blockedBySphereLight(scene, outside, -r.incident, reach, source))
            return;
        const Value tr =
            trackTransmittance(scene.medium(), x, wi, r.distInside, tracker, rng, stats);
        refracted += phase * tr * le * (r.fresnelTransmittance * r.irradianceGain);
    };

    // Chains from x to one source: seed, Newton, trials. `scale` converts the chain's
    // per-unit-strength light into this source's, per channel.
    Value chained(0.f);
    const auto chainFrom = [&](const Light& light, const ChainSource& source, float q,
                               auto&& scale) {
        const std::optional<SpecularChain> seed = chains.sampleSeed(x, rng);
        if (!seed || seed->isSingleRefraction())
            return;  // a single refraction is the search's
        // The seed's own length inside the object (the chain it leads to runs near it).
        const float seedKeep = keepProbability(seed->insideLength(x));
        if (seedKeep < 1.f && rng.uniform() >= seedKeep)
            return;
        const std::optional<SpecularChain> chain = chains.connect(x, *seed, source);
        if (!chain)
            return;
        const Value value =
            chainContribution(scene, x, dirIn, g, path, *chain, light, rng, stats) * scale(*chain);
        const float share = path.largest(value);
        if (!(share > 0.f))
            return;
        const float keep = std::min(1.f, share / (CHAIN_SHARE * (path.largest(refracted) + share)));
        if (keep < 1.f && rng.uniform() >= keep)
            return;
        uint64_t trials = 1;
        for (; trials < MAX_CHAIN_TRIALS; ++trials) {
            const std::optional<SpecularChain> again = chains.sampleSeed(x, rng);
            if (!again || !again->sameKinds(*chain))
                continue;
            const std::optional<SpecularChain> found = chains.connect(x, *again, source);
            if (found && found->sameAs(*chain))
                break;
        }
        if (trials == MAX_CHAIN_TRIALS)
            return;  // never reached in the tests and benchmarks (docs/reference.md)
        chained += value * (float(trials) / (q * seedKeep * keep));
    };

    for (const Light& light : scene.lights()) {
        // The source: a point, a direction, or a point y drawn uniformly on a sphere light
        // (pdf 1/(4πr²)), which emits like a point light of intensity L·cos θy·dA.
        const bool directional = light.type == Light::Type::Directional;
        Vector3f normalAtY(0.f);
        Point3f position = light.position;
        if (light.type == Light::Type::Sphere) {
            normalAtY = uniformSphereDirection(rng);
            position += light.radius * normalAtY;
        }
        const float area = 4.f * PI * light.radius * light.radius;
        const auto sphereFactor = [&](const Vector3f& towardX) {
            return std::max(0.f, glm::dot(normalAtY, towardX)) * area;
        };
        const Vector3f travel = directional ? glm::normalize(light.direction) : Vector3f(0.f);
        const Vector3f toward = directional ? -travel : glm::normalize(position - x);
        // The straight segment towards the source: the roulette's distance and the search's
        // first face.
        const std::optional<SurfaceHit> straight = boundary.intersect(x, toward, 0.f, INF);
        if (!straight)
            continue;  // x is not inside the closed mesh (rounding)
        const float q = keepProbability(straight->t);
        if (q < 1.f && rng.uniform() >= q)
            continue;
        if (directional) {
            search.sampleFromDirection(
                travel, x, eta, boundary, rng.uniform(),
                [&](const Refraction& r, float w) {
                    connect(r, (w / q) * light.intensity, &light);
                },
                straight->triangle);
        } else {
            search.sampleFromPoint(
                position, x, eta, boundary, rng.uniform(),
                [&](const Refraction& r, float w) {
                    const Rgb strength = light.type == Light::Type::Sphere
                                             ? light.intensity * sphereFactor(r.incident)
                                             : light.intensityToward(r.incident);
                    connect(r, (w / q) * strength, &light);
                },
                straight->triangle);
        }
        chainFrom(light, ChainSource{directional ? travel : position, directional}, q,
                  [&](const SpecularChain& chain) {
                      return light.type == Light::Type::Sphere ? sphereFactor(-chain.finalDirection)
                                                               : 1.f;
                  });
    }
    if (scene.environment() != Rgb(0.f)) {
        // A direction drawn uniformly (pdf 1/4π): a directional light of irradiance 4π·L_env.
        const Vector3f travel = -uniformSphereDirection(rng);
        const std::optional<SurfaceHit> straight = boundary.intersect(x, -travel, 0.f, INF);
        const float q = straight ? keepProbability(straight->t) : 1.f;
        if (straight && (q >= 1.f || rng.uniform() < q))
            search.sampleFromDirection(
                travel, x, eta, boundary, rng.uniform(),
                [&](const Refraction& r, float w) {
                    connect(r, (w * 4.f * PI / q) * scene.environment(), nullptr);
                },
                straight->triangle);
    }
    return refracted + chained;
}

/// Next-event estimation from a real collision at x for the boundary model in `options`.
template <typename Path>
typename Path::Value directLighting(const VolumeScene& scene, const Point3f& x,
                                    const Vector3f& dirIn, const typename Path::Value& g,
                                    const Path& path, Pcg32& rng, const TransportOptions& options,
                                    TrackingStats* stats) {
    return refractedNextEvent(options)
               ? refractedLighting(scene, x, dirIn, g, path, rng, options, stats)
               : straightLighting(scene, x, dirIn, g, path, rng, options, stats);
}

/// The camera-path estimator of estimateRadiance / estimateRadianceRgb (Transport.h).
template <typename Path>
typename Path::Value tracePath(const VolumeScene& scene, const Point3f& o, const Vector3f& d,
                               Path& path, Pcg32& rng, const TransportOptions& options,
                               TrackingStats* stats) {
    using Value = typename Path::Value;
    const MeshBoundary& boundary = scene.boundary();
    const GridMedium& medium = scene.medium();
    Value radiance(0.f);
    Point3f pos = o;
    Vector3f dir = glm::normalize(d);
    bool inside = false;
    bool specularChain = true;  // only surface events (no scattering) since the camera
    int scatterCount = 0;
    // Emission found by the path after a scattering event counts only for chains that
    // next-event estimation does not cover: with straight shadow rays, none (they reach every
    // light through the surface); with the refracted estimation, sphere lights are reached
    // through every chain (refraction search and specular chains) and the environment through
    // a single refraction, so only the environment seen through longer chains counts.
    const bool refracted = refractedNextEvent(options);
    int eventsSinceScatter = 0;  // surface events since the last scattering event
    const auto sphereLightCounts = [&] { return specularChain; };
    const auto environmentCounts = [&] {
        return specularChain || (refracted && eventsSinceScatter > 1);
    };
    for (int surfaceEvents = 0; surfaceEvents < MAX_SURFACE_EVENTS;) {
        if (!inside) {
            const std::optional<SurfaceHit> hit = boundary.intersect(pos, dir, 0.f, INF);
            const float tHit = hit ? hit->t : INF;
            // Sphere lights are opaque emitters; so is the environment beyond everything.
            float tLight = INF;
            const Light* emitter = nullptr;
            for (const Light& light : scene.lights()) {
                if (light.type != Light::Type::Sphere)
                    continue;
                const float t = intersectSphere(pos, dir, light.position, light.radius);
                if (t < tLight) {
                    tLight = t;
                    emitter = &light;
                }
            }
            if (tLight < tHit) {
                if (sphereLightCounts())
                    radiance += path.throughput() * path.pick(emitter->intensity);
                break;
            }
            if (!hit) {
                if (environmentCounts())
                    radiance += path.throughput() * path.pick(scene.environment());
                break;
            }
            ++surfaceEvents;
            ++eventsSinceScatter;
            const Point3f x = pos + dir * tHit;
            const Normal3f n = hit->normal;
            const float off = boundary.offsetAt(x);
            if (!path.crossSurface([&](double& w) {
                    return enterSurface(x, n, off, specularChain, pos, dir, inside, w, rng,
                                        options);
                }))
                break;
            continue;
        }
        const std::optional<SurfaceHit> exit = boundary.intersect(pos, dir, 0.f, INF);
        if (!exit) {
            inside = false;  // numerically outside: continue as an outside ray
            continue;
        }
        const std::optional<float> tc =
            trackFreeFlight(medium, pos, dir, exit->t, path, rng, stats);
        if (path.isBlack())
            break;
        if (tc) {
            const Point3f x = pos + dir * *tc;
            if (!path.scatterAlbedo(medium, x) || ++scatterCount > options.maxScatter)
                break;
            const Value g = path.g(medium, x);
            radiance +=
                path.throughput() * directLighting(scene, x, dir, g, path, rng, options, stats);
            specularChain = false;
            eventsSinceScatter = 0;
            if (options.russianRoulette && !path.roulette(rng))
                break;
            dir = path.scatter(dir, g, rng);
            pos = x;
            continue;
        }
        ++surfaceEvents;
        ++eventsSinceScatter;
        const Point3f x = pos + dir * exit->t;
        const Normal3f n = exit->normal;
        const float off = boundary.offsetAt(x);
        path.crossSurface([&](double& w) {
            exitSurface(x, n, off, pos, dir, inside, w, rng, options);
            return true;
        });
    }
    return allFinite(radiance) ? radiance : Value(0.f);
}

}  // namespace

std::optional<float> sampleFreeFlight(const GridMedium& medium, const Point3f& o, const Vector3f& d,
                                      float tMax, int ch, Pcg32& rng, TrackingStats* stats) {
    OneChannel channel{ch};
    return trackFreeFlight(medium, o, d, tMax, channel, rng, stats);
}

float estimateTransmittance(const GridMedium& medium, const Point3f& o, const Vector3f& d,
                            float tMax, int ch, Pcg32& rng, TrackingStats* stats) {
    return trackTransmittance(medium, o, d, tMax, OneChannel{ch}, rng, stats);
}

Rgb estimateTransmittanceRgb(const GridMedium& medium, const Point3f& o, const Vector3f& d,
                             float tMax, Pcg32& rng, TrackingStats* stats) {
    return trackTransmittance(medium, o, d, tMax, AllChannels{}, rng, stats);
}

float shadowTransmittance(const VolumeScene& scene, const Point3f& p, const Vector3f& wi,
                          float dist, bool pInside, int ch, Pcg32& rng,
                          const TransportOptions& options, TrackingStats* stats) {
    return traceShadowRay(scene, p, wi, dist, pInside, OneChannel{ch}, rng, options, stats);
}

WalkResult walkMedium(const VolumeScene& scene, const Point3f& p, const Vector3f& d, int ch,
                      Pcg32& rng, const TransportOptions& options, TrackingStats* stats) {
    WalkResult r;
    const MeshBoundary& boundary = scene.boundary();
    const GridMedium& medium = scene.medium();
    ChannelPath path;  // β: product of albedos and roulette factors
    path.ch = ch;
    Point3f pos = p;
    Vector3f dir = glm::normalize(d);
    int surfaceEvents = 0;
    while (surfaceEvents < MAX_SURFACE_EVENTS) {
        const std::optional<SurfaceHit> exit = boundary.intersect(pos, dir, 0.f, INF);
        if (!exit)
            return r;  // numerically outside the closed mesh: lost
        const std::optional<float> tc =
            trackFreeFlight(medium, pos, dir, exit->t, path, rng, stats);
        if (tc) {
            const Point3f x = pos + dir * *tc;
            // Collision weight: single-scattering albedo σs/σt (analog absorption as weight).
            const bool alive = path.scatterAlbedo(medium, x);
            ++r.scatterCount;
            if (!alive || r.scatterCount > options.maxScatter)
                return r;
            if (options.russianRoulette && !path.roulette(rng))
                return r;
            dir = path.scatter(dir, path.g(medium, x), rng);
            pos = x;
            continue;
        }
        ++surfaceEvents;
        const Point3f x = pos + dir * exit->t;
        // Fresnel reflection back inside or refraction out; the walk follows flux, so the
        // radiance scaling η² that exitSurface applies is dropped.
        double radianceScale = 1.0;
        bool inside = true;
        exitSurface(x, exit->normal, boundary.offsetAt(x), pos, dir, inside, radianceScale, rng,
                    options);
        if (inside)
            continue;
        r.escaped = true;
        r.position = x;
        r.direction = dir;
        r.weight = path.beta;
        return r;
    }
    return r;
}

float estimateRadiance(const VolumeScene& scene, const Point3f& o, const Vector3f& d, int ch,
                       Pcg32& rng, const TransportOptions& options, TrackingStats* stats) {
    ChannelPath path;
    path.ch = ch;
    return tracePath(scene, o, d, path, rng, options, stats);
}

Rgb estimateRadianceRgb(const VolumeScene& scene, const Point3f& o, const Vector3f& d, int hero,
                        Pcg32& rng, const TransportOptions& options, TrackingStats* stats) {
    HeroPath path;
    path.hero = std::clamp(hero, 0, 2);
    return tracePath(scene, o, d, path, rng, options, stats);
}

}  // namespace lucent::reference
