// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Layout of the SSLPV read-out shared by C++ (sslpv/SslpvSolver.cpp, SslpvProvider.cpp)
/// and GLSL (sslpv_sample.comp), so the two cannot drift apart.

/// Mode diffusion sends each surface cell's light out isotropically from the cell (the band-0
/// coefficient holds it, bands 1 and 2 are unused), so the first band-1 coefficient (Y1−1)
/// carries the cell's reduced albedo α′ = σs′/σt′ per channel instead: the read-out
/// interpolates it with the same weights as the light and looks up the exact half-space's
/// exit-angle correction c(α′, t) with it.
#define LUCENT_SSLPV_DIFFUSION_ALBEDO_COEFF 1

/// Shader-storage binding of the exit-angle table (lucent::dipole::DirpoleExitTable, the layout
/// of shared/DirpoleShared.h: LUCENT_DIRPOLE_EXIT_ALBEDO_NODES rows of
/// LUCENT_DIRPOLE_EXIT_COSINE_NODES floats) in sslpv_sample.comp.
#define LUCENT_SSLPV_BINDING_EXIT_TABLE 0
