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

/// Mode diffusion's accumulation grid has the 9 coefficient slots of order 2 whatever the
/// solver's order, and slots 2, 3 and 4 (Y10, Y11, Y2−2) hold each surface cell's flux along the
/// surface J_t (x, y and z, per channel, in the units of the band-0 slot: GridDiffusion::
/// surfaceFlux times the cell's read-out scale), interpolated with the same weights as the
/// light for the P1 exit term (SslpvSolver::exitantRadiance).
#define LUCENT_SSLPV_DIFFUSION_ORDER 2
#define LUCENT_SSLPV_DIFFUSION_FLUX_COEFF 2

/// Texture 0's alpha in the read-out (sslpv_sample.comp, written from SslpvSolver::readoutAlpha):
/// 1 in a cell the read-out interpolates (SslpvSolver::isReadable), else the cell's inside
/// fraction capped at ½, which weights the thin-part read-out (SslpvSolver::
/// thinPartCoefficients). A cell is readable iff its alpha exceeds this value.
#define LUCENT_SSLPV_READABLE_ALPHA_MIN 0.75

/// The thin-part read-out looks for readable cells up to this many cells from the cell nearest
/// its sample point along each axis (a (2R + 1)³ block).
#define LUCENT_SSLPV_THIN_PART_REACH 2

/// Shader-storage binding of the exit-angle table (lucent::dipole::DirpoleExitTable, the layout
/// of shared/DirpoleShared.h: LUCENT_DIRPOLE_EXIT_ALBEDO_NODES rows of
/// LUCENT_DIRPOLE_EXIT_COSINE_NODES floats) in sslpv_sample.comp.
#define LUCENT_SSLPV_BINDING_EXIT_TABLE 0

/// Shader-storage binding of the thin-part pixel list (sslpv_sample.comp): the sample pass
/// appends each pixel that the three read-out depths find no readable cell for, and a second
/// dispatch, sized from the list (glDispatchComputeIndirect), reads only those, so the
/// (2R + 1)³ search no longer runs under the execution mask of every work group that holds one
/// (llvmpipe). Layout (std430, uints): the indirect dispatch's three group counts, the pixel
/// count, then one uint per pixel (x | y << 16).
#define LUCENT_SSLPV_BINDING_THIN_PIXELS 1
#define LUCENT_SSLPV_THIN_PIXELS_HEADER_UINTS 4
/// Work-group size of the thin-part pass (one pixel of the list per invocation), and the most
/// groups the first pass asks for (GL 4.5's guaranteed GL_MAX_COMPUTE_WORK_GROUP_COUNT; past
/// it each invocation takes several pixels).
#define LUCENT_SSLPV_THIN_PASS_GROUP_SIZE 64
#define LUCENT_SSLPV_THIN_PASS_MAX_GROUPS 65535

/// Intervals of the exact half-space's total reflectance table (lucent::sslpv::
/// ExactReflectanceRatio::exactTotals: NODES + 1 values at u_i = i/NODES, α′ = 1 − u_i²), which
/// combined_add.comp interpolates to carry the local kernel to the painted surface's albedo.
#define LUCENT_SSLPV_EXACT_TOTAL_NODES 64
