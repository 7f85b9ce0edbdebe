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

/// Inside flag per voxel centre (voxelCount() bytes, x fastest, 1 = inside).
std::vector<uint8_t> voxelizeSolid(const TriangleMesh& mesh, const GridSpec& spec);

/// Boundary cells: inside cells with at least one face-neighbour outside (same layout).
std::vector<uint8_t> boundaryCells(const std::vector<uint8_t>& inside, const GridSpec& spec);

}  // namespace lucent
