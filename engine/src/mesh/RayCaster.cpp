// SPDX-License-Identifier: MIT
/// @file
/// @brief RayCaster through Embree 3 (the only TU of the engine's ray queries that sees Embree).

#include <lucent/mesh/RayCaster.h>

#include <lucent/core/Error.h>

#include <embree3/rtcore.h>

#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace lucent {

struct RayCaster::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<std::array<uint32_t, 3>> triangles;
    std::vector<Normal3f> vertexNormals;  // empty when the mesh has none (or a size mismatch)
    std::vector<Normal3f> faceNormals;    // unit outward, zero for degenerate triangles

    Impl() = default;
    Impl(const Impl&) = delete;
    Impl& operator=(const Impl&) = delete;
    ~Impl() {
        if (scene)
            rtcReleaseScene(scene);
        if (device)
            rtcReleaseDevice(device);
    }
};

RayCaster::RayCaster(const TriangleMesh& mesh, BvhQuality quality)
    : m_impl(std::make_unique<Impl>()) {
    LUCENT_CHECK(!mesh.isEmpty(), "RayCaster: the mesh has no triangles");
    const size_t nv = mesh.vertexCount();
    for (size_t t = 0; t < mesh.triangleCount(); ++t)
        for (uint32_t v : mesh.triangles[t])
            LUCENT_CHECK(v < nv, "RayCaster: triangle ", t, " has vertex index ", v,
                         " >= vertex count ", nv);
    for (const Point3f& p : mesh.positions)
        LUCENT_CHECK(isFinite(p), "RayCaster: the mesh has a non-finite vertex");
    m_bounds = mesh.bounds();

    Impl& im = *m_impl;
    im.triangles = mesh.triangles;
    if (mesh.normals.size() == nv)
        im.vertexNormals = mesh.normals;
    im.faceNormals.resize(mesh.triangleCount());
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        // (p1 − p0) × (p2 − p0) is outward for counter-clockwise faces; independent of
        // Embree's Ng orientation convention.
        const auto& tri = mesh.triangles[t];
        const Point3f& p0 = mesh.positions[tri[0]];
        const Vector3f n = glm::cross(mesh.positions[tri[1]] - p0, mesh.positions[tri[2]] - p0);
        const float len = glm::length(n);
        im.faceNormals[t] = len > 0.f ? n / len : Normal3f(0.f);
    }

    im.device = rtcNewDevice(nullptr);
    if (!im.device)
        LUCENT_THROW(Error, "RayCaster: Embree device creation failed");
    im.scene = rtcNewScene(im.device);
    // Robust traversal: watertight meshes leak ~1 ray in 10⁶ through shared edges without it
    // (PLATFORM.md).
    rtcSetSceneFlags(im.scene, RTC_SCENE_FLAG_ROBUST);
    if (quality == BvhQuality::High)
        rtcSetSceneBuildQuality(im.scene, RTC_BUILD_QUALITY_HIGH);

    RTCGeometry geom = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_TRIANGLE);
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
    for (size_t t = 0; t < mesh.triangleCount(); ++t)
        for (int k = 0; k < 3; ++k)
            ib[3 * t + k] = mesh.triangles[t][k];
    rtcCommitGeometry(geom);
    rtcAttachGeometry(im.scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(im.scene);
}

RayCaster::~RayCaster() = default;
RayCaster::RayCaster(RayCaster&&) noexcept = default;
RayCaster& RayCaster::operator=(RayCaster&&) noexcept = default;

const Normal3f& RayCaster::faceNormal(uint32_t index) const {
    return m_impl->faceNormals[index];
}

size_t RayCaster::triangleCount() const {
    return m_impl->triangles.size();
}

std::optional<RayCastHit> RayCaster::intersect(const Point3f& o, const Vector3f& d, float tNear,
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
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(m_impl->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return std::nullopt;

    const Impl& im = *m_impl;
    RayCastHit hit;
    hit.t = rh.ray.tfar;
    hit.position = o + hit.t * d;
    hit.triangle = rh.hit.primID;
    const Normal3f& ng = im.faceNormals[hit.triangle];
    hit.geometricNormal = (ng.x != 0.f || ng.y != 0.f || ng.z != 0.f) ? ng : -d;
    hit.shadingNormal = hit.geometricNormal;
    if (!im.vertexNormals.empty()) {
        // Barycentric interpolation with Embree's (u, v): p = (1 − u − v)·p0 + u·p1 + v·p2.
        const auto& tri = im.triangles[hit.triangle];
        const float u = rh.hit.u, v = rh.hit.v;
        const Vector3f ns = (1.f - u - v) * im.vertexNormals[tri[0]] +
                            u * im.vertexNormals[tri[1]] + v * im.vertexNormals[tri[2]];
        const float l = glm::length(ns);
        if (l > 0.f && std::isfinite(l))
            hit.shadingNormal = ns / l;
    }
    return hit;
}

bool RayCaster::occluded(const Point3f& o, const Vector3f& d, float tNear, float tFar) const {
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
    // Embree sets tfar to −∞ when the ray is occluded.
    return ray.tfar == -std::numeric_limits<float>::infinity();
}

}  // namespace lucent
