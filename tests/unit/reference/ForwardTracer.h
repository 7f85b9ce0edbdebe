// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief An independent forward (light) tracer for validating the reference path tracer at a
/// smooth dielectric boundary. It shares no transport code with lucent/reference: its own random
/// numbers (std::mt19937_64), Fresnel equations, Snell refraction, Henyey–Greenstein sampling and
/// analytic geometry (a half-space and a sphere, not the triangle mesh). Photons leave the light,
/// refract exactly, scatter (analog absorption), reflect or refract at every internal crossing
/// (total internal reflection included) and are tallied where they leave after at least one
/// scattering event (light that never scattered is a specular caustic of a delta light, which
/// no camera path can see, and the first-surface reflection is excluded as with
/// --subsurface-only).
///
/// Tallies are fluxes through sets of rays: rays are named by the exit direction ω and, for the
/// sphere, by the point q where the exit ray's line crosses the plane through the sphere's centre
/// perpendicular to the view direction v. The expected tally of a set S of rays is
///   Q(S) = ∫_S L(q, ω) (ω·v) dq dω      (étendue of a bundle crossing the plane ⊥ v),
/// and for the half-space, per unit area of the surface (normal n = +z),
///   Q(C) = ∫_C L(ω) (ω·n) dω,
/// both of which a camera-side estimator measures by averaging radiance over the same rays.

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include <glm/glm.hpp>

namespace lucent::test::forward {

using Vec = glm::dvec3;
constexpr double PI_D = 3.14159265358979323846;

class Random {
public:
    explicit Random(uint64_t seed) : m_engine(seed) {}
    double operator()() { return m_uniform(m_engine); }

private:
    std::mt19937_64 m_engine;
    std::uniform_real_distribution<double> m_uniform{0.0, 1.0};
};

/// Unpolarised reflectance of a smooth interface, incidence cosine c on the side of index n1,
/// transmission into n2 (Fresnel's equations, Hecht, Optics §4.6). 1 for total internal
/// reflection.
inline double reflectance(double c, double n1, double n2) {
    const double s2 = (n1 / n2) * (n1 / n2) * std::max(0.0, 1.0 - c * c);
    if (s2 >= 1.0)
        return 1.0;
    const double ct = std::sqrt(1.0 - s2);
    const double perp = (n1 * c - n2 * ct) / (n1 * c + n2 * ct);
    const double par = (n2 * c - n1 * ct) / (n2 * c + n1 * ct);
    return 0.5 * (perp * perp + par * par);
}

/// Direction after crossing from index n1 to n2 at unit normal `towardIncident` (pointing to
/// the incident side); caller has excluded total internal reflection.
inline Vec transmit(const Vec& d, const Vec& towardIncident, double n1, double n2) {
    const double r = n1 / n2;
    const double c = -glm::dot(d, towardIncident);
    const double ct = std::sqrt(std::max(0.0, 1.0 - r * r * (1.0 - c * c)));
    return glm::normalize(r * d + (r * c - ct) * towardIncident);
}

inline Vec mirror(const Vec& d, const Vec& n) {
    return d - 2.0 * glm::dot(d, n) * n;
}

/// Henyey–Greenstein: new direction around `d` with cos θ drawn by inverting the CDF
/// (Henyey & Greenstein 1941; Jensen et al. 2001 Eq. 6 gives the same inversion).
inline Vec scatterHg(const Vec& d, double g, Random& rnd) {
    const double u = rnd();
    double c;
    if (std::abs(g) < 1e-4) {
        c = 1.0 - 2.0 * u;
    } else {
        const double k = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
        c = (1.0 + g * g - k * k) / (2.0 * g);
    }
    c = std::clamp(c, -1.0, 1.0);
    const double s = std::sqrt(std::max(0.0, 1.0 - c * c));
    const double phi = 2.0 * PI_D * rnd();
    const Vec a = std::abs(d.x) < 0.9 ? Vec(1, 0, 0) : Vec(0, 1, 0);
    const Vec t = glm::normalize(glm::cross(a, d));
    const Vec b = glm::cross(d, t);
    return glm::normalize(s * std::cos(phi) * t + s * std::sin(phi) * b + c * d);
}

/// The medium: constant σt (mm⁻¹), albedo as a function of position, HG asymmetry g.
struct Medium {
    double sigma_t = 1.0;
    std::function<double(const Vec&)> albedo;
    double g = 0.0;
    double eta = 1.3;  ///< inside / outside
};

/// Geometry: where a ray from inside leaves, and the outward normal there.
struct HalfSpace {  // medium at z < 0
    /// Distance along d from p (inside) to the surface, +inf if it never gets there.
    [[nodiscard]] double exitDistance(const Vec& p, const Vec& d) const {
        return d.z > 0.0 ? -p.z / d.z : INFINITY;
    }
    [[nodiscard]] Vec normal(const Vec& /*p*/) const { return {0, 0, 1}; }
};

struct Ball {
    Vec centre{0.0};
    double radius = 1.0;
    [[nodiscard]] double exitDistance(const Vec& p, const Vec& d) const {
        const Vec oc = p - centre;
        const double b = glm::dot(oc, d);
        const double c = glm::dot(oc, oc) - radius * radius;
        return -b + std::sqrt(std::max(0.0, b * b - c));
    }
    [[nodiscard]] Vec normal(const Vec& p) const { return glm::normalize(p - centre); }
};

/// Axis-aligned box [lo, hi] (flat faces: light entering near an edge is totally reflected by
/// the side faces).
struct Box {
    Vec lo{-1.0}, hi{1.0};
    [[nodiscard]] double exitDistance(const Vec& p, const Vec& d) const {
        double t = INFINITY;
        for (int k = 0; k < 3; ++k) {
            if (d[k] > 0.0)
                t = std::min(t, (hi[k] - p[k]) / d[k]);
            else if (d[k] < 0.0)
                t = std::min(t, (lo[k] - p[k]) / d[k]);
        }
        return std::max(0.0, t);
    }
    [[nodiscard]] Vec normal(const Vec& p) const {
        int axis = 0;
        double best = INFINITY, sign = 1.0;
        for (int k = 0; k < 3; ++k) {
            if (std::abs(hi[k] - p[k]) < best) {
                best = std::abs(hi[k] - p[k]);
                axis = k;
                sign = 1.0;
            }
            if (std::abs(p[k] - lo[k]) < best) {
                best = std::abs(p[k] - lo[k]);
                axis = k;
                sign = -1.0;
            }
        }
        Vec n(0.0);
        n[axis] = sign;
        return n;
    }
    /// Where a ray from outside first meets the box (slab method), −1 if it misses.
    [[nodiscard]] double entryDistance(const Vec& o, const Vec& d) const {
        double t0 = 0.0, t1 = INFINITY;
        for (int k = 0; k < 3; ++k) {
            if (d[k] == 0.0) {
                if (o[k] < lo[k] || o[k] > hi[k])
                    return -1.0;
                continue;
            }
            double a = (lo[k] - o[k]) / d[k], b = (hi[k] - o[k]) / d[k];
            if (a > b)
                std::swap(a, b);
            t0 = std::max(t0, a);
            t1 = std::min(t1, b);
        }
        return t0 <= t1 ? t0 : -1.0;
    }
};

/// Follows one photon that has just refracted into the medium at `p` travelling along `d`, until
/// it is absorbed or leaves; calls `exit(position, direction)` when it leaves after at least
/// one scattering event. Analog: weight 1, absorption with probability 1 − albedo.
template <typename Shape, typename Exit>
void walk(const Shape& shape, const Medium& m, Vec p, Vec d, Random& rnd, Exit&& exit) {
    bool scattered = false;
    for (int events = 0; events < 1000000; ++events) {
        const double s = -std::log(1.0 - rnd()) / m.sigma_t;
        const double toSurface = shape.exitDistance(p, d);
        if (s < toSurface) {
            p += s * d;
            if (rnd() >= m.albedo(p))
                return;  // absorbed
            d = scatterHg(d, m.g, rnd);
            scattered = true;
            continue;
        }
        p += toSurface * d;
        const Vec n = shape.normal(p);
        const double c = glm::dot(d, n);  // > 0: leaving
        if (rnd() < reflectance(c, m.eta, 1.0)) {
            d = mirror(d, n);
            p -= 1e-9 * n;
            continue;
        }
        d = transmit(d, -n, m.eta, 1.0);
        if (scattered)
            exit(p, d);
        return;
    }
}

/// Refraction into the medium at the surface point p (outward normal n) of a photon travelling
/// along d; false if it is reflected (the first-surface reflection, not tallied).
inline bool enter(Vec& d, const Vec& n, double eta, Random& rnd) {
    const double c = -glm::dot(d, n);
    if (rnd() < reflectance(c, 1.0, eta))
        return false;
    d = transmit(d, n, 1.0, eta);
    return true;
}

}  // namespace lucent::test::forward
