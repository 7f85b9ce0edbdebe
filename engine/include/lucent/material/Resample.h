// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Resampling of the painted volume to a coarser grid (16³–128³) for the light
/// propagation solver, preserving per-cell transmittance rather than just the mean σ.

#include <lucent/material/MaterialVolume.h>

#include <vector>

namespace lucent {

/// A dense coarse grid of material, SoA, x fastest. Same world box as the source volume.
struct CoarseMaterial {
    GridSpec spec;
    std::vector<float> sigma_t[3];  ///< effective reduced extinction per channel, mm⁻¹
    std::vector<float> sigma_s[3];  ///< effective reduced scattering per channel, mm⁻¹
    std::vector<float> g[3];        ///< scattering-weighted mean asymmetry
    /// fraction of the cell's volume in fine voxels that hold material, [0,1]: the inside mask's
    /// and its boundary skin's (BoundarySkin.h), which the renderers bound by the mesh
    std::vector<float> insideFraction;
    bool homogeneous = false;  ///< every inside cell identical (fast paths may skip reads)
};

/// Resamples `volume` to `resolution`³ cells over the same box. The effective σt of a coarse
/// cell is chosen so that exp(−σt·Δx) equals the mean transmittance across the cell of its
/// fine columns (averaged over the three axes); σs′ keeps the fine cells' albedo weighting.
/// The fine material is the painted value inside the mask and the boundary skin's in the
/// masked-out voxels next to it (the medium the reference renders, GridMedium::fromMaterial):
/// the mesh reaches up to half a voxel past the mask, and a renderer that bounds the cells by
/// the mesh (SslpvRenderer) must find material there.
/// Each cell depends only on the fine voxels it overlaps and their neighbours (whose values the
/// skin mixes); cells are computed in parallel (parallelFor) straight from the brick storage.
/// @throw ValueError if resolution is outside [1, volume.resolution()].
CoarseMaterial resampleForPropagation(const MaterialVolume& volume, int resolution);

/// Whether any cell of the resolution³ grid resampleForPropagation(volume, resolution) fills
/// has at least `fraction` of its volume in inside voxels, without resampling: the inside mask
/// alone is read, cell by cell until the first such cell. The mask holds the voxels whose centre
/// is inside the mesh, so its fraction samples the mesh's own at the material's resolution,
/// which SSLPV's cells keep (their fraction is the mesh's wherever the material, mask and skin,
/// reaches). For the planner, which asks whether SSLPV's grid holds a cell to read
/// (docs/planner.md); reading the mesh's fractions themselves took 0.4 s at grid 64.
/// @throw ValueError if resolution is outside [1, volume.resolution()].
bool anyCoarseCellInside(const MaterialVolume& volume, int resolution, float fraction);

/// Incremental resampling for the live preview: recomputes only the coarse cells of `coarse`
/// that overlap the fine bricks `dirtyBricks` (e.g. volume.takeDirtyBricks() after a stroke)
/// and refreshes `coarse.homogeneous`. The result is bit-identical to
/// resampleForPropagation(volume, coarse.spec.resolution) provided `coarse` was up to date
/// for every brick not listed.
///
///     CoarseMaterial coarse = resampleForPropagation(volume, 32);
///     paint(volume);                                            // strokes mark bricks dirty
///     updateCoarseMaterial(coarse, volume, volume.takeDirtyBricks());
///
/// @param recomputed if given, the recomputed cells' linear indices are appended (ascending).
/// @return the number of coarse cells recomputed.
/// @throw ValueError if `coarse` was not resampled from a volume with this GridSpec (origin,
/// voxel size, resolution), its arrays have the wrong size, or a brick index is out of range.
size_t updateCoarseMaterial(CoarseMaterial& coarse, const MaterialVolume& volume,
                            const std::vector<int>& dirtyBricks,
                            std::vector<int>* recomputed = nullptr);

}  // namespace lucent
