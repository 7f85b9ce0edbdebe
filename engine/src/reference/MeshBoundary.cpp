// SPDX-License-Identifier: MIT
/// @file
/// @brief MeshBoundary through Embree 3 (the only TU that sees Embree headers).

#include <lucent/core/Error.h>
#include <lucent/reference/MeshBoundary.h>

#include <embree3/rtcore.h>

#include <vector>

namespace lucent {

struct MeshBoundary::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<Normal3f> faceNormals;  // outward unit normals (counter-clockwise winding)

    ~Impl() {
        if (scene)
            rtcReleaseScene(scene);
        if (device)
            rtcReleaseDevice(device);
    }
};

MeshBoundary::MeshBoundary(const TriangleMesh& mesh) : m_impl(std::make_unique<Impl>()) {
    LUCENT_CHECK(!mesh.isEmpty(), "MeshBoundary: the mesh has no triangles");
    for (const Point3f& p : mesh.positions)
        LUCENT_CHECK(isFinite(p), "MeshBoundary: the mesh has a non-finite vertex");
    m_bounds = mesh.bounds();

    Impl& im = *m_impl;
    im.device = rtcNewDevice(nullptr);
    if (!im.device)
        LUCENT_THROW(Error, "MeshBoundary: Embree device creation failed");
    im.scene = rtcNewScene(im.device);
    // ROBUST: watertight traversal, no leaks through shared edges of closed meshes.
    rtcSetSceneFlags(im.scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(im.scene, RTC_BUILD_QUALITY_HIGH);

    RTCGeometry geom = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                           RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                           mesh.positions.size()));
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        vb[3 * i + 0] = mesh.positions[i].x;
        vb[3 * i + 1] = mesh.positions[i].y;
        vb[3 * i + 2] = mesh.positions[i].z;
    }
    auto* ib = static_cast<uint32_t*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(uint32_t), mesh.triangles.size()));
    im.faceNormals.resize(mesh.triangles.size());
    const size_t nv = mesh.positions.size();
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        if (tri[0] >= nv || tri[1] >= nv || tri[2] >= nv) {
            rtcReleaseGeometry(geom);
            LUCENT_THROW(ValueError, "MeshBoundary: triangle ", t,
                         " has a vertex index out of range");
        }
        ib[3 * t + 0] = tri[0];
        ib[3 * t + 1] = tri[1];
        ib[3 * t + 2] = tri[2];
        const Point3f& a = mesh.positions[tri[0]];
        const Vector3f n = glm::cross(mesh.positions[tri[1]] - a, mesh.positions[tri[2]] - a);
        const float len = glm::length(n);
        im.faceNormals[t] = len > 0.f ? n / len : Normal3f(0.f, 0.f, 1.f);
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometry(im.scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(im.scene);
}

MeshBoundary::~MeshBoundary() = default;
MeshBoundary::MeshBoundary(MeshBoundary&&) noexcept = default;
MeshBoundary& MeshBoundary::operator=(MeshBoundary&&) noexcept = default;

std::optional<SurfaceHit> MeshBoundary::intersect(const Point3f& o, const Vector3f& d, float tMin,
                                                  float tMax) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    rh.ray.org_x = o.x;
    rh.ray.org_y = o.y;
    rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x;
    rh.ray.dir_y = d.y;
    rh.ray.dir_z = d.z;
    rh.ray.tnear = tMin;
    rh.ray.tfar = std::isfinite(tMax) ? tMax : std::numeric_limits<float>::max();
    rh.ray.time = 0.f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(m_impl->scene, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return std::nullopt;
    return SurfaceHit{rh.ray.tfar, m_impl->faceNormals[rh.hit.primID]};
}

}  // namespace lucent
