// SPDX-License-Identifier: MIT
/// @file
/// @brief Ray–triangle picking (Möller & Trumbore 1997, "Fast, minimum storage ray-triangle
/// intersection", Sec. 2) and slab ray–box rejection (Kay & Kajiya 1986).

#include <lucent/mesh/MeshPicker.h>

#include <algorithm>
#include <cmath>

namespace lucent {

namespace {

bool rayHitsBox(const Bounds3f& b, const Point3f& o, const Vector3f& d) {
    float t0 = 0.f, t1 = INF;
    for (int a = 0; a < 3; ++a) {
        const float inv = 1.f / d[a];
        float tn = (b.lo[a] - o[a]) * inv, tf = (b.hi[a] - o[a]) * inv;
        if (tn > tf)
            std::swap(tn, tf);
        t0 = std::max(t0, tn);
        t1 = std::min(t1, tf);
        if (t0 > t1)
            return false;
    }
    return true;
}

}  // namespace

std::optional<PickHit> pickMesh(const TriangleMesh& mesh, const Point3f& origin,
                                const Vector3f& direction) {
    if (mesh.isEmpty() || !isFinite(origin) || !isFinite(direction))
        return std::nullopt;
    Bounds3f box = mesh.bounds();
    const Vector3f pad(1e-3f * (glm::length(box.extent()) + 1.f));
    box.lo -= pad;
    box.hi += pad;
    if (!rayHitsBox(box, origin, direction))
        return std::nullopt;
    std::optional<PickHit> best;
    float bestT = INF;
    for (uint32_t i = 0; i < mesh.triangles.size(); ++i) {
        const auto& tri = mesh.triangles[i];
        const Point3f& p0 = mesh.positions[tri[0]];
        const Vector3f e1 = mesh.positions[tri[1]] - p0;
        const Vector3f e2 = mesh.positions[tri[2]] - p0;
        // Möller–Trumbore: solve o + t d = p0 + u e1 + v e2 by Cramer's rule (their eq. 5).
        const Vector3f pv = glm::cross(direction, e2);
        const float det = glm::dot(e1, pv);
        if (std::abs(det) < 1e-12f)
            continue;
        const float invDet = 1.f / det;
        const Vector3f tv = origin - p0;
        const float u = glm::dot(tv, pv) * invDet;
        if (u < 0.f || u > 1.f)
            continue;
        const Vector3f qv = glm::cross(tv, e1);
        const float v = glm::dot(direction, qv) * invDet;
        if (v < 0.f || u + v > 1.f)
            continue;
        const float t = glm::dot(e2, qv) * invDet;
        if (t <= 0.f || t >= bestT)
            continue;
        bestT = t;
        PickHit h;
        h.t = t;
        h.position = origin + t * direction;
        Normal3f n = glm::normalize(glm::cross(e1, e2));
        if (glm::dot(n, direction) > 0.f)
            n = -n;
        h.normal = n;
        h.triangle = i;
        best = h;
    }
    return best;
}

}  // namespace lucent
