// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Ray–triangle queries on a TriangleMesh through Embree 3 (RTC_SCENE_FLAG_ROBUST): the
/// one Embree ray-casting wrapper of the engine (Embree stays inside RayCaster.cpp).
///
///     RayCaster caster(mesh);
///     if (auto hit = caster.intersect(o, d, 0.f, INF)) { ... hit->t, hit->geometricNormal ... }
///     bool blocked = caster.occluded(p, l, 0.f, dist);

#include <lucent/core/Types.h>
#include <lucent/mesh/TriangleMesh.h>

#include <cstdint>
#include <memory>
#include <optional>

namespace lucent {

/// A ray's first hit on the mesh.
struct RayCastHit {
    float t = 0.f;                  ///< distance along the ray, mm (units of |d|; d unit → mm)
    Point3f position{0.f};          ///< o + t·d, mm
    Normal3f geometricNormal{0.f};  ///< unit, outward (counter-clockwise faces); −d if degenerate
    Normal3f shadingNormal{0.f};    ///< unit, interpolated vertex normal (geometric if none)
    uint32_t triangle = 0;          ///< index into TriangleMesh::triangles
};

/// Quality of the bounding-volume hierarchy Embree builds (RTC_BUILD_QUALITY_*): High builds
/// slower and may visit triangles in another order; hits are exact either way, only ties
/// (a ray through a shared edge) may resolve to the other triangle.
enum class BvhQuality { Medium, High };

/// A triangle mesh (outward counter-clockwise faces) prepared for ray queries. Queries are
/// thread-safe (const, the Embree scene is committed in the constructor).
class RayCaster {
public:
    /// Copies what the queries need (indices, vertex normals, face normals) from `mesh`.
    /// @throw ValueError if the mesh has no triangles, an out-of-range vertex index or a
    /// non-finite vertex; Error if Embree cannot create a device.
    explicit RayCaster(const TriangleMesh& mesh, BvhQuality quality = BvhQuality::Medium);
    ~RayCaster();
    RayCaster(RayCaster&&) noexcept;
    RayCaster& operator=(RayCaster&&) noexcept;
    RayCaster(const RayCaster&) = delete;
    RayCaster& operator=(const RayCaster&) = delete;

    /// First hit of o + t·d with t ∈ (tNear, tFar] (Embree's ray segment; `tFar` may be +∞).
    /// `d` should be unit for t in mm. Thread-safe.
    [[nodiscard]] std::optional<RayCastHit> intersect(const Point3f& o, const Vector3f& d,
                                                      float tNear, float tFar) const;
    /// True if any triangle is hit by o + t·d for t ∈ (tNear, tFar]. Thread-safe.
    [[nodiscard]] bool occluded(const Point3f& o, const Vector3f& d, float tNear, float tFar) const;

    /// Unit outward normal of triangle `index`, normalize((p1 − p0) × (p2 − p0)); the zero
    /// vector for a degenerate (zero-area) triangle. @pre index < triangleCount().
    [[nodiscard]] const Normal3f& faceNormal(uint32_t index) const;
    [[nodiscard]] size_t triangleCount() const;
    [[nodiscard]] const Bounds3f& bounds() const { return m_bounds; }

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
    Bounds3f m_bounds;
};

}  // namespace lucent
