// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Private: the library boundaries of the mesh module (OpenMesh in OpenMeshBackend.cpp,
/// VTK in VtkBackend.cpp) behind plain functions on TriangleMesh.

#include <lucent/mesh/TriangleMesh.h>

#include <string>

namespace lucent::detail {

/// Result of a raw read, before validation.
struct RawMesh {
    TriangleMesh mesh;
    bool hasNormals = false;             ///< the file provided vertex normals
    size_t nonManifoldDetached = 0;      ///< faces the reader had to detach (OpenMesh)
    size_t readerDroppedDegenerate = 0;  ///< faces with a repeated vertex the reader skipped
};

RawMesh readOpenMesh(const std::string& path);
void writeOpenMesh(const TriangleMesh& mesh, const std::string& path, bool binary);
RawMesh readVtk(const std::string& path);
void writeVtk(const TriangleMesh& mesh, const std::string& path, bool binary);

}  // namespace lucent::detail
