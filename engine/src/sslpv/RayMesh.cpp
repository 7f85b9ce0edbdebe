// SPDX-License-Identifier: MIT
/// @file
/// @brief Embree 3 implementation of the SSLPV renderer's ray queries.

#include "RayMesh.h"

#include <lucent/core/Error.h>

#include <embree3/rtcore.h>

#include <cmath>
#include <limits>

namespace lucent::sslpv_detail {

struct RayMesh::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    TriangleMesh mesh;
    ~Impl() {
        if (scene)
            rtcReleaseScene(scene);
        if (device)
            rtcReleaseDevice(device);
    }
};

RayMesh::RayMesh(const TriangleMesh& mesh) : m_impl(std::make_unique<Impl>()) {
    LUCENT_CHECK(!mesh.isEmpty(), "SSLPV renderer: the mesh has no triangles");
    const size_t nv = mesh.vertexCount();
    for (const auto& tri : mesh.triangles)
        for (uint32_t v : tri)
            LUCENT_CHECK(v < nv, "SSLPV renderer: triangle index ", v, " >= vertex count ", nv);
    for (const auto& p : mesh.positions)
        LUCENT_CHECK(isFinite(p), "SSLPV renderer: the mesh has a non-finite vertex");
    m_impl->mesh = mesh;
    m_bounds = mesh.bounds();
    m_impl->device = rtcNewDevice(nullptr);
    if (!m_impl->device)
        LUCENT_THROW(Error, "SSLPV renderer: Embree device creation failed");
    m_impl->scene = rtcNewScene(m_impl->device);
    // Robust traversal: watertight meshes leak ~1 ray in 10⁶ without it (PLATFORM.md).
    rtcSetSceneFlags(m_impl->scene, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry geom = rtcNewGeometry(m_impl->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv));
    for (size_t i = 0; i < nv; ++i) {
        vb[3 * i + 0] = mesh.positions[i].x;
        vb[3 * i + 1] = mesh.positions[i].y;
        vb[3 * i + 2] = mesh.positions[i].z;
    }
    auto* ib = static_cast<uint32_t*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(uint32_t), mesh.triangleCount()));
    for (size_t i = 0; i < mesh.triangleCount(); ++i)
        for (int k = 0; k < 3; ++k)
            ib[3 * i + k] = mesh.triangles[i][k];
    rtcCommitGeometry(geom);
    rtcAttachGeometry(m_impl->scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(m_impl->scene);
}

RayMesh::~RayMesh() = default;

std::optional<RayHit> RayMesh::intersect(const Point3f& o, const Vector3f& d, float tNear,
                                         float tFar) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh{};
    rh.ray.org_x = o.x;
    rh.ray.org_y = o.y;
    rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x;
    rh.ray.dir_y = d.y;
    rh.ray.dir_z = d.z;
    rh.ray.tnear = tNear;
    rh.ray.tfar = tFar;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(m_impl->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return std::nullopt;
    RayHit hit;
    hit.t = rh.ray.tfar;
    hit.position = o + hit.t * d;
    // Geometric normal from the vertices: (p1 − p0) × (p2 − p0) is outward for our
    // counter-clockwise faces; independent of Embree's Ng orientation convention.
    const auto& tri = m_impl->mesh.triangles[rh.hit.primID];
    const Point3f& p0 = m_impl->mesh.positions[tri[0]];
    const Point3f& p1 = m_impl->mesh.positions[tri[1]];
    const Point3f& p2 = m_impl->mesh.positions[tri[2]];
    Vector3f ng = glm::cross(p1 - p0, p2 - p0);
    const float len = glm::length(ng);
    ng = len > 0.f ? ng / len : -d;
    hit.geometricNormal = ng;
    hit.shadingNormal = ng;
    if (m_impl->mesh.normals.size() == m_impl->mesh.positions.size()) {
        const float u = rh.hit.u, v = rh.hit.v;
        const Vector3f ns = (1.f - u - v) * m_impl->mesh.normals[tri[0]] +
                            u * m_impl->mesh.normals[tri[1]] + v * m_impl->mesh.normals[tri[2]];
        const float l = glm::length(ns);
        if (l > 0.f && std::isfinite(l))
            hit.shadingNormal = ns / l;
    }
    return hit;
}

bool RayMesh::occluded(const Point3f& o, const Vector3f& d, float tNear, float tFar) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay ray{};
    ray.org_x = o.x;
    ray.org_y = o.y;
    ray.org_z = o.z;
    ray.dir_x = d.x;
    ray.dir_y = d.y;
    ray.dir_z = d.z;
    ray.tnear = tNear;
    ray.tfar = tFar;
    ray.mask = 0xFFFFFFFFu;
    rtcOccluded1(m_impl->scene, &ctx, &ray);
    return ray.tfar == -std::numeric_limits<float>::infinity();
}

}  // namespace lucent::sslpv_detail
