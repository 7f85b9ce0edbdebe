// SPDX-License-Identifier: MIT
/// @file
/// @brief Specular chains traced backwards with ray differentials (SpecularChain.h,
/// docs/reference.md "Chains of surface events").
///
/// Ray differentials through planar interfaces: transfer dP' = dP + t·dD + dt·D with
/// dt = −(dP + t·dD)·n / (D·n); reflection dD' = dD − 2(dD·n)n; refraction with μ = n₁/n₂,
/// c = −D·n, c_t = √(1 − μ²(1 − c²)): D' = μD + (μc − c_t)n and
/// dD' = μ·dD + (μ·dc − dc_t)·n, dc = −dD·n, dc_t = μ²·c·dc/c_t (Igehy 1999, "Tracing ray
/// differentials", Sec. 3.3, with dn = 0 on a flat face).

#include <lucent/core/Fresnel.h>
#include <lucent/core/Sampling.h>
#include <lucent/reference/SpecularChain.h>
#include <lucent/reference/Transport.h>

#include <algorithm>
#include <cmath>

namespace lucent::reference {

namespace {

using Vec3d = glm::dvec3;

constexpr int MAX_NEWTON_STEPS = 24;
/// Step halvings of the line search before Newton's method gives up.
constexpr int MAX_HALVINGS = 6;
/// Largest change of the direction at x in one Newton step (radians): keeps the walk on the
/// faces near the current chain.
constexpr double MAX_STEP = 0.25;
/// Converged: the end ray points at the source within this angle (radians; float positions
/// limit the attainable accuracy to ~1e-7 relative).
constexpr double CONVERGED_ANGLE = 2e-6;

/// A backward trace with its end ray and the two columns of the end ray's derivative with
/// respect to the direction at x (per radian along the frame's a and b).
struct Trace {
    SpecularChain chain;
    Point3f end{0.f};                          ///< last event point
    Vec3d derivativeA{0.0}, derivativeB{0.0};  ///< at the source: ⊥ position or direction
    Vec3d offset{0.0};  ///< source minus the end ray, ⊥ to it (point) / direction error
};

/// One surface crossing of a ray travelling along dir at the surface point with outward
/// normal n. Returns the Fresnel reflectance (1 under total internal reflection).
double reflectance(const Vec3d& dir, const Vec3d& n, bool inside, double eta, double& cosI,
                   Vec3d& incidentNormal) {
    incidentNormal = inside ? -n : n;  // on the side the ray comes from
    cosI = -glm::dot(dir, incidentNormal);
    return fresnelDielectric(float(cosI), inside ? float(1.0 / eta) : float(eta));
}

}  // namespace

bool SpecularChain::sameKinds(const SpecularChain& other) const {
    return events == other.events &&
           std::equal(reflects.begin(), reflects.begin() + events, other.reflects.begin());
}

bool SpecularChain::sameAs(const SpecularChain& other) const {
    if (events != other.events)
        return false;
    for (int i = 0; i < events; ++i)
        if (faces[size_t(i)] != other.faces[size_t(i)] ||
            reflects[size_t(i)] != other.reflects[size_t(i)])
            return false;
    return true;
}

float SpecularChain::insideLength(const Point3f& x) const {
    float length = 0.f;
    Point3f from = x;
    for (int i = 0; i < events; ++i) {
        if (insideBefore[size_t(i)])
            length += glm::length(points[size_t(i)] - from);
        from = points[size_t(i)];
    }
    return length;
}

SpecularChainTracer::SpecularChainTracer(const MeshBoundary& boundary, float eta)
    : m_boundary(&boundary), m_eta(eta) {}

std::optional<SpecularChain> SpecularChainTracer::sampleSeed(const Point3f& x, Pcg32& rng) const {
    SpecularChain chain;
    const Vector3f v = sampleUniformSphere({rng.uniform(), rng.uniform()});
    chain.directionAtX = v;
    Point3f pos = x;
    Vec3d dir(v);
    bool inside = true;
    for (;;) {
        const std::optional<SurfaceHit> hit = m_boundary->intersect(pos, Vector3f(dir), 0.f, INF);
        if (!hit) {
            if (inside)
                return std::nullopt;  // numerically outside the closed mesh
            chain.finalDirection = Vector3f(dir);
            return chain;
        }
        if (chain.events == SpecularChain::MAX_EVENTS)
            return std::nullopt;
        const Point3f p = pos + Vector3f(dir) * hit->t;
        double cosI;
        Vec3d nI;
        const double f = reflectance(dir, Vec3d(hit->normal), inside, m_eta, cosI, nI);
        if (!(cosI > 0.0))
            return std::nullopt;
        const bool reflect = f >= 1.0 || rng.uniform() < 0.5f;
        const size_t i = size_t(chain.events++);
        chain.faces[i] = hit->triangle;
        chain.reflects[i] = reflect;
        chain.points[i] = p;
        chain.insideBefore[i] = inside;
        const float off = m_boundary->offsetAt(p);
        if (reflect) {
            dir = glm::normalize(dir + 2.0 * cosI * nI);
            pos = p + Vector3f(nI) * off;
        } else {
            const double mu = inside ? m_eta : 1.0 / m_eta;
            const double ct = std::sqrt(std::max(0.0, 1.0 - mu * mu * (1.0 - cosI * cosI)));
            dir = glm::normalize(mu * dir + (mu * cosI - ct) * nI);
            pos = p - Vector3f(nI) * off;
            inside = !inside;
        }
    }
}

namespace {

std::optional<Trace> traceWithDifferentials(const MeshBoundary& boundary, double eta,
                                            const Point3f& x, const Vector3f& v,
                                            const SpecularChain& kinds, const ChainSource& source) {
    Trace tr;
    SpecularChain& chain = tr.chain;
    chain.directionAtX = v;
    const Frame frame(v);
    Vec3d dPa(0.0), dPb(0.0), dDa(frame.s), dDb(frame.t);
    Point3f pos = x;
    Vec3d dir(v);
    bool inside = true;
    for (int i = 0; i < kinds.events; ++i) {
        const std::optional<SurfaceHit> hit = boundary.intersect(pos, Vector3f(dir), 0.f, INF);
        if (!hit)
            return std::nullopt;
        const Point3f p = pos + Vector3f(dir) * hit->t;
        double cosI;
        Vec3d nI;
        const double f = reflectance(dir, Vec3d(hit->normal), inside, eta, cosI, nI);
        if (!(cosI > 1e-7))
            return std::nullopt;
        // Transfer the differentials to the face's plane.
        const double t = double(hit->t);
        const double dn = glm::dot(dir, nI);
        for (auto* d : {&dPa, &dPb}) {
            const Vec3d& dD = d == &dPa ? dDa : dDb;
            const Vec3d moved = *d + t * dD;
            *d = moved - (glm::dot(moved, nI) / dn) * dir;
        }
        const size_t k = size_t(i);
        chain.faces[k] = hit->triangle;
        chain.reflects[k] = kinds.reflects[k];
        chain.points[k] = p;
        chain.insideBefore[k] = inside;
        chain.events = i + 1;
        const float off = boundary.offsetAt(p);
        if (kinds.reflects[k]) {
            chain.fresnel *= f;
            dir = glm::normalize(dir + 2.0 * cosI * nI);
            dDa -= 2.0 * glm::dot(dDa, nI) * nI;
            dDb -= 2.0 * glm::dot(dDb, nI) * nI;
            pos = p + Vector3f(nI) * off;
        } else {
            if (f >= 1.0)
                return std::nullopt;  // total internal reflection: no refraction here
            chain.fresnel *= 1.0 - f;
            const double mu = inside ? eta : 1.0 / eta;
            const double ct = std::sqrt(std::max(1e-12, 1.0 - mu * mu * (1.0 - cosI * cosI)));
            for (Vec3d* dD : {&dDa, &dDb}) {
                const double dc = -glm::dot(*dD, nI);
                const double dct = mu * mu * cosI * dc / ct;
                *dD = mu * *dD + (mu * dc - dct) * nI;
            }
            dir = mu * dir + (mu * cosI - ct) * nI;
            const double len = glm::length(dir);
            dir /= len;
            dDa /= len;
            dDb /= len;
            pos = p - Vector3f(nI) * off;
            inside = !inside;
        }
    }
    if (inside || kinds.events == 0)
        return std::nullopt;  // a chain ends outside, towards the light
    chain.finalDirection = Vector3f(dir);
    tr.end = pos;
    // The end ray against the source, as an angle: the tangent vector at the end direction
    // that turns it onto the direction towards the source (the log map on the sphere), and
    // its derivatives. A point source at distance r sees the end ray's position move by
    // dP⊥ + r·dD across the ray, i.e. by (dP⊥ + r·dD)/r in angle; a direction sees dD.
    const auto across = [&](const Vec3d& w) { return w - glm::dot(w, dir) * dir; };
    Vec3d toward;
    double distance = 1.0;
    if (source.isDirection) {
        toward = -glm::normalize(Vec3d(source.value));
        tr.derivativeA = across(dDa);
        tr.derivativeB = across(dDb);
        chain.distanceToSource = INF;
    } else {
        const Vec3d w = Vec3d(source.value) - Vec3d(pos);
        distance = glm::length(w);
        if (!(distance > 0.0))
            return std::nullopt;
        toward = w / distance;
        tr.derivativeA = across(dPa + distance * dDa);
        tr.derivativeB = across(dPb + distance * dDb);
        chain.distanceToSource = float(distance);
    }
    const Vec3d side = across(toward);
    const double sideLength = glm::length(side);
    const double angle = std::atan2(sideLength, glm::dot(toward, dir));
    tr.offset = sideLength > 0.0 ? side * (angle / sideLength) : Vec3d(0.0);
    // Étendue: n_x²·dA·dΩ_x is conserved, so the forward pencil from the source (unit solid
    // angle, or unit area for a direction) spreads over η²·dΩ_x/(end-ray area or solid angle
    // per dΩ_x) at x; the columns are per radian of two orthonormal directions: dΩ_x = 1.
    const double area = glm::length(glm::cross(tr.derivativeA, tr.derivativeB));
    if (!(area > 0.0))
        return std::nullopt;
    chain.irradianceGain = eta * eta / area;
    tr.derivativeA /= distance;
    tr.derivativeB /= distance;
    return tr;
}

/// Whether a converged chain really reaches the source: the last segment must leave towards
/// it, unobstructed by the object.
bool reachesSource(const MeshBoundary& boundary, const Trace& t, const ChainSource& source) {
    const SpecularChain& c = t.chain;
    const float reach = source.isDirection ? INF : c.distanceToSource;
    return !boundary.occluded(t.end, c.finalDirection, 0.f, reach);
}

}  // namespace

std::optional<SpecularChain> SpecularChainTracer::trace(const Point3f& x, const Vector3f& v,
                                                        const SpecularChain& kinds,
                                                        const ChainSource& source) const {
    const std::optional<Trace> t = traceWithDifferentials(*m_boundary, m_eta, x, v, kinds, source);
    if (!t || !reachesSource(*m_boundary, *t, source))
        return std::nullopt;
    return t->chain;
}

std::optional<SpecularChain> SpecularChainTracer::connect(const Point3f& x,
                                                          const SpecularChain& seed,
                                                          const ChainSource& source) const {
    Vector3f v = seed.directionAtX;
    std::optional<Trace> t = traceWithDifferentials(*m_boundary, m_eta, x, v, seed, source);
    if (!t)
        return std::nullopt;
    double error = glm::length(t->offset);
    for (int step = 0; step < MAX_NEWTON_STEPS; ++step) {
        if (error <= CONVERGED_ANGLE) {
            if (!reachesSource(*m_boundary, *t, source))
                return std::nullopt;
            return t->chain;
        }
        // Gauss–Newton on the angle between the end ray and the source: J·δ = offset for a
        // change δ of the direction at x (two angles along the frame's s and t), with
        // backtracking: a step that breaks the chain (a refraction meets total internal
        // reflection, a ray misses) or does not reduce the angle is halved.
        const Vec3d& a = t->derivativeA;
        const Vec3d& b = t->derivativeB;
        const double aa = glm::dot(a, a), ab = glm::dot(a, b), bb = glm::dot(b, b);
        const double det = aa * bb - ab * ab;
        if (!(det > 0.0))
            return std::nullopt;
        const double ea = glm::dot(a, t->offset), eb = glm::dot(b, t->offset);
        double da = (bb * ea - ab * eb) / det, db = (aa * eb - ab * ea) / det;
        const double len = std::hypot(da, db);
        if (len > MAX_STEP) {
            da *= MAX_STEP / len;
            db *= MAX_STEP / len;
        }
        const Frame frame(v);
        bool improved = false;
        for (int halving = 0; halving < MAX_HALVINGS && !improved; ++halving) {
            const Vector3f next = glm::normalize(v + float(da) * frame.s + float(db) * frame.t);
            std::optional<Trace> candidate =
                traceWithDifferentials(*m_boundary, m_eta, x, next, seed, source);
            if (candidate && glm::length(candidate->offset) < error) {
                v = next;
                t = std::move(candidate);
                error = glm::length(t->offset);
                improved = true;
            }
            da *= 0.5;
            db *= 0.5;
        }
        if (!improved)
            return std::nullopt;
    }
    return std::nullopt;
}

}  // namespace lucent::reference
