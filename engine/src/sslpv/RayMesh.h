// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Private: Embree ray queries on a triangle mesh for the CPU SSLPV renderer (RSM texels,
/// primary visibility, shadow rays). Embree stays inside RayMesh.cpp.

#include <lucent/core/Types.h>
#include <lucent/mesh/TriangleMesh.h>

#include <memory>
#include <optional>

namespace lucent::sslpv_detail {

struct RayHit {
    float t = 0.f;
    Point3f position{0.f};
    Normal3f geometricNormal{0.f};  ///< unit, outward (counter-clockwise faces)
    Normal3f shadingNormal{0.f};    ///< unit, interpolated vertex normal (geometric if none)
};

class RayMesh {
public:
    /// @throw ValueError for an empty mesh or bad indices; GpuError never (CPU only).
    explicit RayMesh(const TriangleMesh& mesh);
    ~RayMesh();
    RayMesh(const RayMesh&) = delete;
    RayMesh& operator=(const RayMesh&) = delete;

    /// First hit of o + t·d, t ∈ (tNear, tFar]; d unit. Thread-safe.
    [[nodiscard]] std::optional<RayHit> intersect(const Point3f& o, const Vector3f& d, float tNear,
                                                  float tFar) const;
    /// True if anything blocks o + t·d for t ∈ (tNear, tFar). Thread-safe.
    [[nodiscard]] bool occluded(const Point3f& o, const Vector3f& d, float tNear, float tFar) const;
    [[nodiscard]] const Bounds3f& bounds() const { return m_bounds; }

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
    Bounds3f m_bounds;
};

}  // namespace lucent::sslpv_detail
