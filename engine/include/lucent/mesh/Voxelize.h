// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Solid voxelisation: which cells of a GridSpec lie inside a mesh. Robust on meshes
/// that are not watertight (see docs/conventions.md for the rule used).

#include <lucent/material/MaterialVolume.h>
#include <lucent/mesh/TriangleMesh.h>

#include <cstdint>
#include <vector>

namespace lucent {

/// Inside flag per voxel centre (voxelCount() bytes, x fastest, 1 = inside): three-axis ray
/// parity with per-column rays and voting (docs/conventions.md, "Voxels"). The grid may cover
/// any part of the mesh; an empty mesh gives all zeros.
/// @param mesh triangles in mm (any orientation; open meshes are handled by the voting).
/// @param spec the grid, resolution in [1, 1024].
/// @throw ValueError for an invalid GridSpec, a non-finite vertex or an out-of-range index.
std::vector<uint8_t> voxelizeSolid(const TriangleMesh& mesh, const GridSpec& spec);

/// Boundary cells: inside cells with at least one face-neighbour outside (same layout); cells
/// beyond the grid count as outside.
/// @throw ValueError if inside.size() != spec.voxelCount().
std::vector<uint8_t> boundaryCells(const std::vector<uint8_t>& inside, const GridSpec& spec);

}  // namespace lucent
