// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Private: checks of mesh files before an upstream reader sees them
/// (docs/file-formats.md, "Import limits"). OpenMesh's readers trust the counts and list
/// lengths a file gives (a mutated face valence of 4·10⁹ makes its OFF reader push indices
/// from a failed stream for minutes and gigabytes), so the whole body of every OpenMesh format
/// is walked here first: every count within the import limits and the file size, every
/// element present (a truncated file is an error, not a smaller mesh), every index in range.
/// Legacy .vtk files are walked in full too: VTK 9.1's legacy reader reads on from a failed
/// stream and crashed in-process on nearly every malformed file. The work is one pass over the
/// file. VTK formats are then read in a child process (VtkBackend.cpp); for .vtp only the
/// header and the cell offsets are checked here, and what the headers claim is compared with
/// what VTK read.

#include <cstdint>
#include <string>

namespace lucent::detail {

/// Element counts a VTK file's header claims (0 when it does not say).
struct ClaimedCounts {
    uint64_t points = 0;
    uint64_t polygons = 0;
};

/// Checks the file named `path` (extension `ext`, lower case, with the dot; `size` bytes) in
/// full for the OpenMesh formats (.obj .ply .off .stl) and legacy .vtk, its header and cell
/// offsets for .vtp.
/// @return what a VTK header claims (zero for the other formats).
/// @throw IoError naming the file, the line or byte and the problem.
ClaimedCounts validateMeshFile(const std::string& path, const std::string& ext, uint64_t size);

}  // namespace lucent::detail
