// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Mesh import/export: OBJ, PLY (ASCII/binary), OFF, STL through OpenMesh; VTP/VTK
/// through VTK. Every loaded mesh is validated (see validateMesh) and scaled to millimetres.
///
///     MeshReport report;
///     TriangleMesh m = loadMesh("bunny.ply", /*scale=*/100.f, &report);  // file units → mm
///     for (const auto& w : report.warnings) log(w);

#include <lucent/mesh/TriangleMesh.h>

#include <string>
#include <vector>

namespace lucent {

/// What validation found and repaired. Repairs are applied to the mesh; every repair and every
/// topological problem left in place has a line in `warnings`.
struct MeshReport {
    size_t inputTriangles = 0;       ///< triangles before repair (after triangulating polygons)
    size_t degenerateDropped = 0;    ///< faces with repeated vertices or zero area, removed
    size_t duplicateDropped = 0;     ///< faces with the same vertex set as an earlier face, removed
    size_t unreferencedDropped = 0;  ///< vertices used by no face, removed
    size_t boundaryEdges = 0;        ///< edges with one face: the mesh is open (holes)
    size_t nonManifoldEdges = 0;     ///< edges shared by more than two faces
    bool normalsComputed = false;    ///< the file had no (valid) vertex normals
    std::vector<std::string> warnings;

    /// True when every edge has exactly two faces.
    [[nodiscard]] bool isClosedManifold() const {
        return boundaryEdges == 0 && nonManifoldEdges == 0;
    }
};

/// Checks and repairs a mesh in place: drops degenerate and duplicate faces and unreferenced
/// vertices, counts boundary and non-manifold edges, recomputes normals when missing/invalid.
/// @param name used in messages (e.g. the file name).
/// @throw ValueError if a vertex is NaN/Inf, an index is out of range, or no face remains.
MeshReport validateMesh(TriangleMesh& mesh, const std::string& name = "mesh");

/// Loads a triangle mesh. Polygons are triangulated. Format by extension (case-insensitive):
/// .obj .ply .off .stl (OpenMesh), .vtp .vtk (VTK).
/// @param scale file units → mm (e.g. 1000 for a file in metres), > 0.
/// @param report optional: receives what validation found.
/// @throw IoError naming the file if it is missing, unreadable, malformed, empty or has
///        non-finite coordinates; ValueError for a bad scale.
TriangleMesh loadMesh(const std::string& path, float scale = 1.f, MeshReport* report = nullptr);

/// Writes a mesh with vertex normals; format by extension as for loadMesh.
/// @param binary PLY/STL: binary encoding (VTP: appended binary); ignored for OBJ/OFF/VTK.
/// @throw IoError naming the file on failure.
void saveMesh(const TriangleMesh& mesh, const std::string& path, bool binary = true);

}  // namespace lucent
