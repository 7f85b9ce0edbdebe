// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Private: the library boundaries of the mesh module (OpenMesh in OpenMeshBackend.cpp,
/// VTK in VtkBackend.cpp) behind plain functions on TriangleMesh.

#include "MeshValidate.h"

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
/// Reads .vtp/.vtk in a child process with resource limits; `claimed` (from the header) must
/// match what VTK read.
RawMesh readVtk(const std::string& path, const ClaimedCounts& claimed);
void writeVtk(const TriangleMesh& mesh, const std::string& path, bool binary);

}  // namespace lucent::detail
