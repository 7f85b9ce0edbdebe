// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Warps from [0,1)² to directions and discs, with their densities, and local frames.

#include <lucent/core/Types.h>

namespace lucent {

/// Orthonormal frame with `n` as its z axis (Duff et al. 2017, branchless ONB).
struct Frame {
    Vector3f s, t, n;
    explicit Frame(const Normal3f& normal) : n(normal) {
        const float sign = std::copysign(1.f, n.z);
        const float a = -1.f / (sign + n.z);
        const float b = n.x * n.y * a;
        s = Vector3f(1.f + sign * n.x * n.x * a, sign * b, -sign * n.x);
        t = Vector3f(b, sign + n.y * n.y * a, -n.y);
    }
    [[nodiscard]] Vector3f toWorld(const Vector3f& v) const { return v.x * s + v.y * t + v.z * n; }
    [[nodiscard]] Vector3f toLocal(const Vector3f& v) const {
        return {glm::dot(v, s), glm::dot(v, t), glm::dot(v, n)};
    }
};

/// Uniform direction on the unit sphere; pdf = 1/(4π) sr⁻¹.
inline Vector3f sampleUniformSphere(Point2f u) {
    const float z = 1.f - 2.f * u.x;
    const float r = std::sqrt(std::max(0.f, 1.f - z * z));
    const float phi = 2.f * PI * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

/// Concentric map of [0,1)² to the unit disc (Shirley–Chiu); uniform in area.
inline Point2f sampleConcentricDisc(Point2f u) {
    const Point2f o = 2.f * u - Point2f(1.f);
    if (o.x == 0.f && o.y == 0.f)
        return {0.f, 0.f};
    float r, theta;
    if (std::abs(o.x) > std::abs(o.y)) {
        r = o.x;
        theta = (PI / 4.f) * (o.y / o.x);
    } else {
        r = o.y;
        theta = (PI / 2.f) - (PI / 4.f) * (o.x / o.y);
    }
    return {r * std::cos(theta), r * std::sin(theta)};
}

/// Cosine-weighted direction about +z; pdf = cos θ / π.
inline Vector3f sampleCosineHemisphere(Point2f u) {
    const Point2f d = sampleConcentricDisc(u);
    const float z = std::sqrt(std::max(0.f, 1.f - d.x * d.x - d.y * d.y));
    return {d.x, d.y, z};
}

/// Samples the Henyey–Greenstein phase function about the propagation direction `wo`
/// (the direction light travels before scattering). Returns the new travel direction;
/// pdf equals hgPhase(g, dot(wo, result)).
inline Vector3f sampleHenyeyGreenstein(const Vector3f& wo, float g, Point2f u) {
    float cosTheta;
    if (std::abs(g) < 1e-3f) {
        cosTheta = 1.f - 2.f * u.x;
    } else {
        const float sq = (1.f - g * g) / (1.f + g - 2.f * g * u.x);
        cosTheta = (1.f + g * g - sq * sq) / (2.f * g);
    }
    cosTheta = std::clamp(cosTheta, -1.f, 1.f);
    const float sinTheta = std::sqrt(std::max(0.f, 1.f - cosTheta * cosTheta));
    const float phi = 2.f * PI * u.y;
    const Frame f(wo);
    return f.toWorld({sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta});
}

}  // namespace lucent
