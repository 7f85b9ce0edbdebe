// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Shared by the SSLPV unit tests: a coarse material to fill, ball injection texels, a
/// headless GL context.

#include <lucent/material/Resample.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace lucent::test {

/// N³ cells of h mm centred on the origin, every cell σt, σs′ (mm⁻¹) and g as given, no
/// inside cell yet.
inline CoarseMaterial centredMaterial(int n, float h, float sigma_t = 0.f, float sigma_s = 0.f,
                                      float g = 0.f) {
    CoarseMaterial m;
    m.spec.resolution = n;
    m.spec.voxelSize = h;
    m.spec.origin = Point3f(-0.5f * n * h);
    const size_t count = m.spec.voxelCount();
    m.insideFraction.assign(count, 0.f);
    for (int c = 0; c < 3; ++c) {
        m.sigma_t[c].assign(count, sigma_t);
        m.sigma_s[c].assign(count, sigma_s);
        m.g[c].assign(count, g);
    }
    return m;
}

/// Texels of an orthographic RSM of a directional light travelling along `dir` onto the ball
/// of radius 0.35·N·h at the grid's centre: `texels`² texels over its disc, texel area a (mm²)
/// times irradiance E (W/mm²) gives Φ_p (§3.1, directional case).
inline std::vector<sslpv::SslpvInjectionSample> ballTexels(const CoarseMaterial& m, Vector3f dir,
                                                           Rgb E, int texels = 48) {
    dir = glm::normalize(dir);
    const float radius = 0.35f * m.spec.resolution * m.spec.voxelSize;
    const Vector3f a = std::abs(dir.x) < 0.9f ? Vector3f(1, 0, 0) : Vector3f(0, 1, 0);
    const Vector3f u = glm::normalize(glm::cross(dir, a)), v = glm::cross(dir, u);
    const float pitch = 2.f * radius / texels;
    std::vector<sslpv::SslpvInjectionSample> out;
    for (int j = 0; j < texels; ++j)
        for (int i = 0; i < texels; ++i) {
            const float s = (i + 0.5f) * pitch - radius, t = (j + 0.5f) * pitch - radius;
            const float r2 = s * s + t * t;
            if (r2 >= radius * radius)
                continue;
            const Point3f p = s * u + t * v - std::sqrt(radius * radius - r2) * dir;
            out.push_back({p, glm::normalize(p), dir, E * pitch * pitch});
        }
    return out;
}

}  // namespace lucent::test
