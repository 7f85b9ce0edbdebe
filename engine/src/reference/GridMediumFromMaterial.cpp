// SPDX-License-Identifier: MIT
/// @file
/// @brief GridMedium::fromMaterial: the painted volume through the shared mapping toMedium().

#include <lucent/reference/GridMedium.h>

#include <lucent/material/BoundarySkin.h>

namespace lucent::reference {

GridMedium GridMedium::fromMaterial(const MaterialVolume& volume, const Options& options) {
    const GridSpec& spec = volume.spec();
    std::vector<MediumCoefficients> voxels(spec.voxelCount());
    const int r = spec.resolution;
    for (int z = 0; z < r; ++z)
        for (int y = 0; y < r; ++y)
            for (int x = 0; x < r; ++x) {
                const Coord c(x, y, z);
                // at() is zero for masked-out voxels: empty (vacuum) unless in the skin below.
                // σa = σt − σs′, σs = σs′/(1−g) (Medium.h, the shared mapping).
                voxels[spec.linearIndex(c)] = toMedium(volume.at(c));
            }
    // The mesh bounds the medium, and its interior reaches past the mask's voxel centres into
    // the masked-out voxels it partly fills: those read the material of their inside
    // neighbours, not vacuum (BoundarySkin.h). Voxels further out are never reached inside
    // the mesh and stay empty.
    for (const SkinVoxel& s : boundarySkin(volume))
        voxels[s.index] = toMedium(s.value);
    return GridMedium(spec, voxels, options);
}

}  // namespace lucent::reference
