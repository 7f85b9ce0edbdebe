// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Tables of the directional-dipole passes, shared by C++ (dipole/DirpoleProvider.cpp)
/// and GLSL (dirpole_gather.comp, dirpole_combine.comp), so their sizes cannot drift apart.

/// Nodes of the energy-normalisation table (uniform float u_energyScale[]): DirpoleEnergyTable
/// resampled uniformly in s = √(1 − α′) over [0, 1].
#define LUCENT_DIRPOLE_ENERGY_NODES 256

/// The exit-angle correction of the exact target (lucent::dipole::DirpoleExitTable): an SSBO of
/// LUCENT_DIRPOLE_EXIT_ALBEDO_NODES × LUCENT_DIRPOLE_EXIT_COSINE_NODES floats, one row per
/// albedo node (uniform in s = √(1 − α′) over [0, 1]), one column per outside cosine node
/// t_j = j / (LUCENT_DIRPOLE_EXIT_COSINE_NODES − 1).
#define LUCENT_DIRPOLE_EXIT_ALBEDO_NODES 64
#define LUCENT_DIRPOLE_EXIT_COSINE_NODES 16
#define LUCENT_DIRPOLE_BINDING_EXIT_TABLE 9

/// The incidence correction of the exact target (lucent::dipole::DirpoleIncidenceTable): an SSBO
/// of LUCENT_DIRPOLE_INCIDENCE_ALBEDO_NODES × LUCENT_DIRPOLE_INCIDENCE_COSINE_NODES floats, one
/// row per albedo node (uniform in s = √(1 − α′)), one column per refracted cosine node (uniform
/// over [μ_min, 1], μ_min a uniform of the gather pass).
#define LUCENT_DIRPOLE_INCIDENCE_ALBEDO_NODES 24
#define LUCENT_DIRPOLE_INCIDENCE_COSINE_NODES 8
#define LUCENT_DIRPOLE_BINDING_INCIDENCE_TABLE 10
