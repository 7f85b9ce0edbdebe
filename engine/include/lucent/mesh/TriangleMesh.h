// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Indexed triangle mesh in millimetres: the plain exchange type between mesh I/O
/// (OpenMesh/VTK, kept in .cpp files), voxelisation, ray tracing and GPU upload.

#include <lucent/core/Types.h>

#include <array>
#include <cstdint>
#include <vector>

namespace lucent {

/// Indexed triangles with per-vertex normals. Counter-clockwise faces seen from outside.
struct TriangleMesh {
    std::vector<Point3f> positions;                  ///< mm
    std::vector<Normal3f> normals;                   ///< unit, per vertex (same size as positions)
    std::vector<std::array<uint32_t, 3>> triangles;  ///< vertex indices

    [[nodiscard]] bool isEmpty() const { return triangles.empty(); }
    [[nodiscard]] size_t vertexCount() const { return positions.size(); }
    [[nodiscard]] size_t triangleCount() const { return triangles.size(); }
    [[nodiscard]] Bounds3f bounds() const {
        Bounds3f b;
        for (const auto& p : positions)
            b.expand(p);
        return b;
    }
};

/// Recomputes per-vertex normals as area-weighted face normals.
void computeVertexNormals(TriangleMesh& mesh);

}  // namespace lucent
