// SPDX-License-Identifier: MIT
/// @file
/// @brief MeshBoundary on top of the mesh module's RayCaster (which holds the Embree scene).

#include <lucent/reference/MeshBoundary.h>

#include <lucent/mesh/RayCaster.h>

#include <cmath>
#include <limits>

namespace lucent::reference {

struct MeshBoundary::Impl {
    explicit Impl(const TriangleMesh& mesh) : caster(mesh, BvhQuality::High) {}
    RayCaster caster;
};

MeshBoundary::MeshBoundary(const TriangleMesh& mesh)
    : m_impl(std::make_unique<Impl>(mesh)), m_bounds(m_impl->caster.bounds()) {}

MeshBoundary::~MeshBoundary() = default;
MeshBoundary::MeshBoundary(MeshBoundary&&) noexcept = default;
MeshBoundary& MeshBoundary::operator=(MeshBoundary&&) noexcept = default;

std::optional<SurfaceHit> MeshBoundary::intersect(const Point3f& o, const Vector3f& d, float tMin,
                                                  float tMax) const {
    // An infinite tMax is clamped to the largest float (the segment is then bounded for
    // Embree); the same (tMin, tMax] segment as RayCaster otherwise.
    const float tFar = std::isfinite(tMax) ? tMax : std::numeric_limits<float>::max();
    const auto hit = m_impl->caster.intersect(o, d, tMin, tFar);
    if (!hit)
        return std::nullopt;
    // The face normal; a degenerate (zero-area) triangle reports +z, as it always has.
    const Normal3f& n = m_impl->caster.faceNormal(hit->triangle);
    const bool degenerate = n.x == 0.f && n.y == 0.f && n.z == 0.f;
    return SurfaceHit{hit->t, degenerate ? Normal3f(0.f, 0.f, 1.f) : n, hit->triangle};
}

bool MeshBoundary::occluded(const Point3f& o, const Vector3f& d, float tMin, float tMax) const {
    const float tFar = std::isfinite(tMax) ? tMax : std::numeric_limits<float>::max();
    return m_impl->caster.occluded(o, d, tMin, tFar);
}

}  // namespace lucent::reference
