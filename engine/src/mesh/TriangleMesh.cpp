// SPDX-License-Identifier: MIT
/// @file
/// @brief TriangleMesh helpers: area-weighted vertex normals.

#include <lucent/mesh/TriangleMesh.h>

namespace lucent {

void computeVertexNormals(TriangleMesh& mesh) {
    std::vector<Vector3f> acc(mesh.positions.size(), Vector3f(0.f));
    for (const auto& t : mesh.triangles) {
        const Point3f& a = mesh.positions[t[0]];
        const Point3f& b = mesh.positions[t[1]];
        const Point3f& c = mesh.positions[t[2]];
        // The cross product's length is twice the triangle area: area weighting for free.
        const Vector3f n = glm::cross(b - a, c - a);
        for (uint32_t v : t)
            acc[v] += n;
    }
    mesh.normals.resize(mesh.positions.size());
    for (size_t i = 0; i < acc.size(); ++i) {
        const float len = glm::length(acc[i]);
        mesh.normals[i] = len > 0.f && std::isfinite(len) ? acc[i] / len : Normal3f(0.f, 0.f, 1.f);
    }
}

}  // namespace lucent
