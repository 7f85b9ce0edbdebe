// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Constants of the combined mode shared by C++ (combined/Combined.cpp,
/// combined/CombinedProvider.cpp) and GLSL (combined_add.comp), so the two cannot drift apart.

/// Points of the disc r <= r_s at which discMeanMaterial reads the surface's material (Hammersley
/// points, uniform in area): the material the light L-hat integrates crosses on its way to x_o.
/// 16 took the painted veins' and bunny's errors to what 32 gave on the CPU path
/// (docs/methods/combined.md, "The kernel at the painted surface").
#define LUCENT_COMBINED_DISC_MEAN_SAMPLES 16
