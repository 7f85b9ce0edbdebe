// SPDX-License-Identifier: MIT
/// @file
/// @brief Procedural closed meshes: icosphere, tessellated box, torus and the thin-thick shape.

#include <lucent/core/Error.h>
#include <lucent/mesh/Procedural.h>

#include <cmath>
#include <map>
#include <utility>

namespace lucent {
namespace {

/// Flips every triangle whose geometric normal points toward `centre` of its local frame, as
/// judged by `outward(p)`: keeps all faces counter-clockwise seen from outside.
template <typename OutwardFn>
void orientOutward(TriangleMesh& mesh, OutwardFn outward) {
    for (auto& t : mesh.triangles) {
        const Point3f a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
        const Vector3f n = glm::cross(b - a, c - a);
        if (glm::dot(n, outward((a + b + c) / 3.f)) < 0.f)
            std::swap(t[1], t[2]);
    }
}

/// Unit icosphere: an icosahedron split `subdivisions` times (each triangle into four, new
/// vertices projected back onto the sphere).
TriangleMesh unitIcosphere(int subdivisions) {
    TriangleMesh m;
    const float phi = (1.f + std::sqrt(5.f)) * 0.5f;
    const float raw[12][3] = {{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
                              {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
                              {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
    for (const auto& r : raw)
        m.positions.push_back(glm::normalize(Point3f(r[0], r[1], r[2])));
    m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                   {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                   {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                   {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (int s = 0; s < subdivisions; ++s) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            const auto key = std::minmax(a, b);
            auto it = midpoints.find(key);
            if (it != midpoints.end())
                return it->second;
            const auto idx = uint32_t(m.positions.size());
            m.positions.push_back(glm::normalize(m.positions[a] + m.positions[b]));
            midpoints.emplace(key, idx);
            return idx;
        };
        std::vector<std::array<uint32_t, 3>> next;
        next.reserve(m.triangles.size() * 4);
        for (const auto& t : m.triangles) {
            const uint32_t ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]),
                           ca = midpoint(t[2], t[0]);
            next.push_back({t[0], ab, ca});
            next.push_back({t[1], bc, ab});
            next.push_back({t[2], ca, bc});
            next.push_back({ab, bc, ca});
        }
        m.triangles = std::move(next);
    }
    orientOutward(m, [](const Point3f& p) { return p; });
    return m;
}

float smoothstep(float e0, float e1, float x) {
    const float t = std::clamp((x - e0) / (e1 - e0), 0.f, 1.f);
    return t * t * (3.f - 2.f * t);
}

}  // namespace

TriangleMesh makeSphere(float radius, int subdivisions) {
    LUCENT_CHECK(std::isfinite(radius) && radius > 0.f, "sphere radius must be > 0 mm, got ",
                 radius);
    LUCENT_CHECK(subdivisions >= 0 && subdivisions <= 7,
                 "sphere subdivisions must be in [0, 7], got ", subdivisions);
    TriangleMesh m = unitIcosphere(subdivisions);
    m.normals = m.positions;  // exact normals of the unit sphere
    for (auto& p : m.positions)
        p *= radius;
    return m;
}

TriangleMesh makeBox(const Vector3f& size) {
    LUCENT_CHECK(isFinite(size) && size.x > 0.f && size.y > 0.f && size.z > 0.f,
                 "box size must be three positive lengths in mm");
    // Each face is an N×N grid of quads so deformers (twist, bend) have vertices to move.
    constexpr int N = 8;
    TriangleMesh m;
    std::map<std::array<int, 3>, uint32_t> index;  // lattice point on the surface → vertex
    auto vertex = [&](int i, int j, int k) {
        const std::array<int, 3> key{i, j, k};
        auto it = index.find(key);
        if (it != index.end())
            return it->second;
        const auto idx = uint32_t(m.positions.size());
        m.positions.push_back((Point3f(i, j, k) / float(N) - 0.5f) * size);
        index.emplace(key, idx);
        return idx;
    };
    for (int axis = 0; axis < 3; ++axis) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        for (int side = 0; side <= N; side += N) {
            for (int a = 0; a < N; ++a) {
                for (int b = 0; b < N; ++b) {
                    std::array<int, 3> c00{}, c10{}, c11{}, c01{};
                    for (auto* c : {&c00, &c10, &c11, &c01})
                        (*c)[axis] = side;
                    c00[u] = a, c00[v] = b;
                    c10[u] = a + 1, c10[v] = b;
                    c11[u] = a + 1, c11[v] = b + 1;
                    c01[u] = a, c01[v] = b + 1;
                    const uint32_t i00 = vertex(c00[0], c00[1], c00[2]);
                    const uint32_t i10 = vertex(c10[0], c10[1], c10[2]);
                    const uint32_t i11 = vertex(c11[0], c11[1], c11[2]);
                    const uint32_t i01 = vertex(c01[0], c01[1], c01[2]);
                    m.triangles.push_back({i00, i10, i11});
                    m.triangles.push_back({i00, i11, i01});
                }
            }
        }
    }
    // Outward = the face's axis direction (from the centre through the face centroid's
    // dominant coordinate, relative to the box half-size).
    orientOutward(m, [&](const Point3f& p) {
        const Vector3f q = p / size;
        const Vector3f aq = glm::abs(q);
        Vector3f n(0.f);
        const int ax = aq.x >= aq.y && aq.x >= aq.z ? 0 : aq.y >= aq.z ? 1 : 2;
        n[ax] = q[ax] > 0.f ? 1.f : -1.f;
        return n;
    });
    computeVertexNormals(m);
    return m;
}

TriangleMesh makeTorus(float majorRadius, float minorRadius, int majorSegments, int minorSegments) {
    LUCENT_CHECK(std::isfinite(majorRadius) && std::isfinite(minorRadius) && minorRadius > 0.f &&
                     majorRadius > minorRadius,
                 "torus radii must satisfy major > minor > 0 mm, got major ", majorRadius,
                 ", minor ", minorRadius);
    LUCENT_CHECK(
        majorSegments >= 3 && minorSegments >= 3 && majorSegments <= 4096 && minorSegments <= 4096,
        "torus segment counts must be in [3, 4096]");
    TriangleMesh m;
    for (int i = 0; i < majorSegments; ++i) {
        const float u = 2.f * PI * float(i) / float(majorSegments);
        const Vector3f ring(std::cos(u), 0.f, std::sin(u));  // ring direction in the xz plane
        for (int j = 0; j < minorSegments; ++j) {
            const float v = 2.f * PI * float(j) / float(minorSegments);
            const Normal3f n = std::cos(v) * ring + std::sin(v) * Vector3f(0.f, 1.f, 0.f);
            m.positions.push_back(majorRadius * ring + minorRadius * n);
            m.normals.push_back(n);
        }
    }
    auto id = [&](int i, int j) {
        return uint32_t((i % majorSegments) * minorSegments + (j % minorSegments));
    };
    for (int i = 0; i < majorSegments; ++i) {
        for (int j = 0; j < minorSegments; ++j) {
            m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    }
    orientOutward(m, [&](const Point3f& p) {
        const Vector3f radial = glm::normalize(Vector3f(p.x, 0.f, p.z));
        return p - majorRadius * radial;  // from the tube's core line outward
    });
    return m;
}

TriangleMesh makeThinThick(float size) {
    LUCENT_CHECK(std::isfinite(size) && size > 0.f, "thin-thick size must be > 0 mm, got ", size);
    // A unit icosphere mapped by (x, y, z) ↦ (w·x, h(|x|)·y, t(|x|)·z): each slice x = const
    // (a circle of radius ρ = √(1−x²)) becomes an ellipse with half-axes ρ·h (height, y) and
    // ρ·t (thickness, z). Near x = 0, h = t = body radius (a thick ball); for |x| past the
    // body, h grows while t shrinks to a thin fin ("ear") in the xy plane. The Jacobian is
    // triangular with diagonal (w, h, t) > 0, so the map is an orientation-preserving
    // embedding: the result stays a closed, outward 2-manifold.
    TriangleMesh m = unitIcosphere(5);
    constexpr float BODY_R = 0.30f;  // body radius, fraction of the final height
    constexpr float EAR_H = 0.55f;   // ear half-height scale
    constexpr float EAR_T = 0.035f;  // ear half-thickness scale (thin part)
    constexpr float HALF_WIDTH = 0.65f;
    for (auto& p : m.positions) {
        const float u = std::abs(p.x);
        const float s = smoothstep(0.3f, 0.6f, u);  // 0 in the body, 1 in the ears
        const float h = (1.f - s) * BODY_R + s * EAR_H;
        const float t = (1.f - s) * BODY_R + s * EAR_T;
        p = Point3f(p.x * HALF_WIDTH, p.y * h, p.z * t);
    }
    // Normalise to the documented overall height `size` (y extent), centred at the origin.
    const Bounds3f b = m.bounds();
    const float k = size / (b.hi.y - b.lo.y);
    const Point3f c = b.center();
    for (auto& p : m.positions)
        p = (p - c) * k;
    computeVertexNormals(m);
    return m;
}

}  // namespace lucent
