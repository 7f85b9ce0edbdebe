// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Constants of the image-space dipole provider shared by C++ (dipole/DipoleProvider.cpp)
/// and GLSL (dipole_material.glsl, dipole_material_update.comp), so the two cannot drift apart.

/// How far from a surface point's voxel, floor((p − origin)/h), dipoleMaterialInside reads, in
/// voxels per axis: rule 1 steps at most 3 voxels along −n (3 with the floors), rule 2's shells
/// reach 4 around a voxel at most 1 from it; one more for rounding. A pixel whose voxel is
/// further than this from every changed voxel looks up the same material. The material update
/// marks the bricks within one brick of a written one, so it must not exceed a brick's edge
/// (MaterialVolume::BRICK).
#define LUCENT_DIPOLE_MATERIAL_REACH 6
