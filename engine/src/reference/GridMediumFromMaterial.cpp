// SPDX-License-Identifier: MIT
/// @file
/// @brief GridMedium::fromMaterial: the painted volume through the shared mapping toMedium().

#include <lucent/reference/GridMedium.h>

namespace lucent::reference {

GridMedium GridMedium::fromMaterial(const MaterialVolume& volume, const Options& options) {
    const GridSpec& spec = volume.spec();
    std::vector<MediumCoefficients> voxels(spec.voxelCount());
    const int r = spec.resolution;
    for (int z = 0; z < r; ++z)
        for (int y = 0; y < r; ++y)
            for (int x = 0; x < r; ++x) {
                const Coord c(x, y, z);
                // at() is zero for masked-out voxels: they become empty (vacuum) cells.
                // σa = σt − σs′, σs = σs′/(1−g) (Medium.h, the shared mapping).
                voxels[spec.linearIndex(c)] = toMedium(volume.at(c));
            }
    return GridMedium(spec, voxels, options);
}

}  // namespace lucent::reference
