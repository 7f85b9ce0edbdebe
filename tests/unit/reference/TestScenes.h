// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Small analytic set-ups for the path-tracer tests: box meshes and grids.

#include <lucent/core/Sampling.h>
#include <lucent/mesh/TriangleMesh.h>
#include <lucent/reference/GridMedium.h>
#include <lucent/reference/Transport.h>

#include <array>
#include <functional>

namespace lucent::test {

/// Axis-aligned box [lo, hi] as 12 triangles, counter-clockwise seen from outside.
inline TriangleMesh boxMesh(const Point3f& lo, const Point3f& hi) {
    TriangleMesh m;
    for (int i = 0; i < 8; ++i)
        m.positions.push_back(
            {(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
    // Faces as quads (a, b, c, d); the winding is fixed below from the outward direction.
    const int quads[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                             {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
    const Point3f c = 0.5f * (lo + hi);
    for (const auto& q : quads) {
        for (const std::array<int, 3>& t :
             {std::array<int, 3>{q[0], q[1], q[2]}, std::array<int, 3>{q[0], q[2], q[3]}}) {
            const Point3f a = m.positions[t[0]], b = m.positions[t[1]], d = m.positions[t[2]];
            const Vector3f n = glm::cross(b - a, d - a);
            const bool outward = glm::dot(n, (a + b + d) / 3.f - c) > 0.f;
            m.triangles.push_back(
                outward ? std::array<uint32_t, 3>{uint32_t(t[0]), uint32_t(t[1]), uint32_t(t[2])}
                        : std::array<uint32_t, 3>{uint32_t(t[0]), uint32_t(t[2]), uint32_t(t[1])});
        }
    }
    m.normals.assign(m.positions.size(), Normal3f(0.f, 0.f, 1.f));
    return m;
}

/// Grid of `res`³ voxels of size h starting at `origin`, value from `f(i, j, k)`.
inline reference::GridMedium gridFrom(const Point3f& origin, float h, int res,
                                      const std::function<MediumCoefficients(int, int, int)>& f,
                                      const reference::GridMedium::Options& options) {
    GridSpec spec;
    spec.origin = origin;
    spec.voxelSize = h;
    spec.resolution = res;
    std::vector<MediumCoefficients> v(spec.voxelCount());
    for (int k = 0; k < res; ++k)
        for (int j = 0; j < res; ++j)
            for (int i = 0; i < res; ++i)
                v[spec.linearIndex({i, j, k})] = f(i, j, k);
    return reference::GridMedium(spec, v, options);
}

/// Coefficients with the same σt, σs, g in all three channels.
inline MediumCoefficients grey(float sigma_t, float sigma_s, float g = 0.f) {
    MediumCoefficients m;
    m.sigma_t = Rgb(sigma_t);
    m.sigma_s = Rgb(sigma_s);
    m.sigma_a = Rgb(sigma_t - sigma_s);
    m.g = Rgb(g);
    return m;
}

/// Running mean and standard error of i.i.d. samples.
struct MeanSe {
    double sum = 0, sumSq = 0;
    long n = 0;
    void add(double x) {
        sum += x;
        sumSq += x * x;
        ++n;
    }
    [[nodiscard]] double mean() const { return sum / double(n); }
    /// Standard error of the mean: √(s²/n).
    [[nodiscard]] double se() const {
        const double m = mean();
        return std::sqrt(std::max(0.0, (sumSq / double(n) - m * m) / double(n - 1)));
    }
};

/// Fluence (W/mm²) at `probe` from the scene's lights via the object (channel 0): directions
/// sampled uniformly in the cone around the object's bounding sphere (radius `radius` about
/// `centre`, probe outside it), pdf = 1/(2π(1 − cos θmax)); fluence = E[L / pdf] (radiance
/// from outside the cone is zero: the lights here are points or directional).
inline MeanSe fluenceAt(const reference::VolumeScene& scene, const Point3f& probe,
                        const Point3f& centre, float radius, int n, uint64_t seed,
                        const reference::TransportOptions& to) {
    Pcg32 rng(seed);
    MeanSe f;
    const Vector3f axis = centre - probe;
    const float d2 = glm::dot(axis, axis);
    const float cosMax = std::sqrt(1.f - radius * radius / d2);
    const double invPdf = 2.0 * PI * (1.0 - cosMax);
    const Frame frame(axis / std::sqrt(d2));
    for (int i = 0; i < n; ++i) {
        const float cosT = 1.f - rng.uniform() * (1.f - cosMax);
        const float sinT = std::sqrt(std::max(0.f, 1.f - cosT * cosT));
        const float phi = 2.f * PI * rng.uniform();
        const Vector3f d = frame.toWorld({sinT * std::cos(phi), sinT * std::sin(phi), cosT});
        f.add(invPdf * reference::estimateRadiance(scene, probe, glm::normalize(d), 0, rng, to));
    }
    return f;
}

inline MediumCoefficients lumpy(int i, int j, int k) {
    const float s = 0.2f + 0.25f * float((i * 5 + j * 11 + k * 3) % 6);
    return grey(s, 0.8f * s, 0.3f);
}

}  // namespace lucent::test
