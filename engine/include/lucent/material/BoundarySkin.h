// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The material that continues past the inside mask into the voxels the mesh only
/// partly fills.
///
///     for (const SkinVoxel& s : boundarySkin(volume))
///         coefficients[s.index] = toMedium(s.value);   // what a mesh-bounded renderer reads
///
/// The inside mask holds the voxels whose *centre* is inside the mesh (voxelizeSolid), so the
/// mesh's interior reaches up to half a voxel past the mask on a face (further at edges and
/// corners). A renderer bounded by the mesh that reads the masked-out value there sees a
/// vacuum skin under the surface: at 48³ on a 3 mm slab whose faces cross voxels, a sixth of a
/// millimetre of vacuum under each face and a third of a millimetre along two of its edges.
/// The skin gives those voxels the material of their nearest inside neighbours instead.

#include <lucent/material/Medium.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace lucent {

class MaterialVolume;

/// A masked-out voxel next to the inside, with the material that continues into it.
struct SkinVoxel {
    size_t index = 0;      ///< linear voxel index (GridSpec::linearIndex)
    MaterialSample value;  ///< the mixture of its nearest inside neighbours
};

/// Every voxel outside the inside mask that shares a face, an edge or a corner with an inside
/// voxel, valued as the mixture of its nearest inside neighbours: the face neighbours if it has
/// any, else the edge neighbours, else the corner ones. The mixture of media in equal volumes
/// (σ in mm⁻¹): σt and σs′ are the means, g the σs-weighted mean (the mixed phase function's
/// mean cosine; σs = σs′/(1−g) unreduced, the similarity relation of Wyman et al. 1989), so the
/// mixture's σs′ = mean σs(1−g) is again the mean σs′. Sorted by index; empty when every voxel
/// is inside or none is.
std::vector<SkinVoxel> boundarySkin(const MaterialVolume& volume);

/// The value boundarySkin gives voxel c (inside the grid): the mixture of its nearest inside
/// neighbours, or nothing when c is inside or has no inside neighbour. For readers that need the
/// skin of a few voxels (resampleForPropagation reads it cell by cell).
std::optional<MaterialSample> skinValue(const MaterialVolume& volume, const Coord& c);

/// Per brick (MaterialVolume's brick order): 1 when it or a brick next to it holds an inside
/// voxel. A voxel's neighbours lie in its brick or the bricks next to it, so no voxel of an
/// unflagged brick is in the skin: the cheap test that skips the empty space around an object.
std::vector<uint8_t> bricksNearInside(const MaterialVolume& volume);

}  // namespace lucent
