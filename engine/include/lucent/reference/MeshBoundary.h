// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The object's surface for the path tracer: ray–triangle queries through the mesh
/// module's RayCaster (Embree, RTC_SCENE_FLAG_ROBUST, kept out of this header).
///
///     MeshBoundary boundary(mesh);
///     if (auto hit = boundary.intersect(o, d, 0.f, INF)) { ... hit->t, hit->normal ... }

#include <lucent/core/Types.h>
#include <lucent/mesh/TriangleMesh.h>

#include <memory>
#include <optional>

namespace lucent::reference {

/// A ray's first surface crossing.
struct SurfaceHit {
    float t = 0.f;          ///< distance along the (unit) ray direction, mm
    Normal3f normal{0.f};   ///< unit geometric normal of the triangle, pointing out of the object
    uint32_t triangle = 0;  ///< index into the mesh's triangles
};

/// A closed triangle mesh (outward counter-clockwise faces) as the medium's boundary.
class MeshBoundary {
public:
    /// @throw ValueError if the mesh is empty, has out-of-range indices or non-finite vertices.
    explicit MeshBoundary(const TriangleMesh& mesh);
    ~MeshBoundary();
    MeshBoundary(MeshBoundary&&) noexcept;
    MeshBoundary& operator=(MeshBoundary&&) noexcept;
    MeshBoundary(const MeshBoundary&) = delete;
    MeshBoundary& operator=(const MeshBoundary&) = delete;

    /// First crossing of o + t·d with t ∈ (tMin, tMax]; `d` must be unit. Thread-safe.
    [[nodiscard]] std::optional<SurfaceHit> intersect(const Point3f& o, const Vector3f& d,
                                                      float tMin, float tMax) const;
    /// True if the segment o + t·d, t ∈ (tMin, tMax], meets the surface (a cheaper query than
    /// intersect when only visibility matters). `d` must be unit. Thread-safe.
    [[nodiscard]] bool occluded(const Point3f& o, const Vector3f& d, float tMin, float tMax) const;
    [[nodiscard]] const Bounds3f& bounds() const { return m_bounds; }
    /// Offset (mm) that moves a point on the surface off it robustly: scales with the
    /// magnitude of the coordinates (float spacing) and is never below 1e-5 mm.
    [[nodiscard]] float offsetAt(const Point3f& p) const {
        const float m = std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)});
        return 1e-5f + 4e-6f * m;
    }

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
    Bounds3f m_bounds;
};

}  // namespace lucent::reference
