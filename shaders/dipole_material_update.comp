#version 450 core
// SPDX-License-Identifier: MIT
// Material update of dipole::DipoleSubsurfaceProvider after a paint stroke (docs/methods/dipole.md
// §3c, "Material-only restarts"). A pixel's running sum Σ_f B_f(x_o) depends on the material only
// through σt and σs′ just inside x_o: the profile R_d, the samplers and the disc radius R′ are
// x_o's (Mertens et al. 2005 §5), and the irradiance E, the G-buffer and the light views do not
// depend on the material at all. So a pixel whose looked-up material differs from the one its sum
// was computed with restarts (sum and frame count 0) and stores the new σt, σs′ and R′; every
// other pixel keeps its sum. The restarted pixels and every covered pixel with fewer than u_level
// frames (earlier strokes' pixels still catching up) are listed for the stroke's preview and the
// catch-up gather (dipole_provider.comp with u_listCount > 0), with the fewest frames of any
// listed pixel. (u_level 0: the accumulation's frame 0 is still under way; it overwrites every
// pixel, so the restarted ones are listed for the preview only.)
//
// Two passes, because llvmpipe runs a branch's code for every lane of a SIMD group when any
// lane takes it (and much of it when none does): the SCAN variant visits every covered pixel and
// lists those whose look-up reaches a brick written since the last update (a pixel whose voxel
// is further than the look-up's reach from every changed voxel looks up the same material:
// LUCENT_DIPOLE_MATERIAL_REACH, shared/DipoleShared.h); the default variant looks up the listed
// pixels only. A stroke's update went from 6.2–6.5 to ~2 ms at 640×360 on llvmpipe.
#include "dipole_material.glsl"
#include "dipole_profiles.glsl"
#include "common/dispatch.glsl"

#ifdef SCAN
layout(local_size_x = 8, local_size_y = 8) in;
#else
layout(local_size_x = 64) in;
#endif

layout(binding = 0) uniform sampler2D u_position;  // G-buffer: xyz mm, a coverage
layout(binding = 1) uniform sampler2D u_normal;    // unit normal, a mesh id + 1
layout(binding = 3) uniform sampler3D u_volumeSigmaT;  // rgb σt (mm⁻¹), a inside
layout(binding = 4) uniform sampler3D u_volumeSigmaS;  // rgb σs′ (mm⁻¹)

layout(rgba32f, binding = 0) uniform image2D u_accum;   // rgb Σ_f B_f (W/mm²), a frames
layout(rgba32f, binding = 1) uniform image2D u_sigmaT;  // σt (mm⁻¹) the sum was computed with
layout(rgba32f, binding = 2) uniform image2D u_sigmaS;  // rgb σs′ (mm⁻¹), a R′ (mm)
// min and max of R′ (floats ≥ 0 order like their bit patterns): widened by the restarted pixels.
layout(std430, binding = 3) buffer RadiusBlock { uint b_minRadius; uint b_maxRadius; };
// Counts (zeroed by the host, b_minFrames = ~0) and the list, x | y << 16 per pixel.
layout(std430, binding = 4) buffer UpdateBlock {
    uint b_listed;
    uint b_restarted;
    uint b_minFrames;
    uint b_pad;
    uint b_list[];
};
// The pixels to look up, x | y << 16: the SCAN pass writes it, the look-up pass reads it.
layout(std430, binding = 5) buffer LookupBlock {
    uint b_lookupCount;
    uint b_lookupPad[3];
    uint b_lookup[];
};
#ifdef SCAN
// One word per brick of the painted volume: non-zero within one brick of a brick written since
// the last update (VolumeTextures::takeWrittenBricks; one brick ≥ the look-up's reach).
layout(std430, binding = 6) readonly buffer ReachBlock { uint b_reached[]; };
uniform int u_reachAll;  // every pixel is looked up (a full upload)
uniform int u_bricksPerAxis;
uniform int u_brick;  // voxels per brick edge
#endif

uniform ivec2 u_size;
uniform int u_hasMaterial;
uniform vec3 u_gridOrigin;  // mm
uniform float u_voxelSize;  // mm
uniform int u_resolution;
uniform int u_model;      // 0 dipole, 1 better dipole
uniform vec3 u_boundary;  // F_dr, C1, C2
uniform float u_discQuantile;
uniform float u_maxRadius;  // mm; > 0: R′ is capped at the local-radius window
uniform int u_meshId;       // −1: every mesh; else only pixels of this mesh
uniform int u_level;        // frames of the accumulation: pixels below it are listed

// Lists the pixel for the preview and the catch-up when it restarted or is behind u_level.
void listIfBehind(ivec2 xy, vec4 acc, bool restarted) {
    uint frames = uint(max(acc.a, 0.0) + 0.5);  // a stroke's preview (alpha −1): no frame
    if (restarted || frames < uint(u_level)) {
        b_list[atomicAdd(b_listed, 1u)] = uint(xy.x) | (uint(xy.y) << 16);
        atomicMin(b_minFrames, frames);
    }
}

#ifdef SCAN
void main() {
    ivec2 xy = ivec2(gl_GlobalInvocationID.xy);
    if (xy.x >= u_size.x || xy.y >= u_size.y) return;
    vec4 pos = texelFetch(u_position, xy, 0);
    vec4 normalId = texelFetch(u_normal, xy, 0);
    bool ours = u_meshId < 0 || int(normalId.a + 0.5) - 1 == u_meshId;
    // The irradiance pass stored σ = 0 for the other pixels, and they never gather.
    if (pos.w == 0.0 || !ours) return;
    bool reached = u_reachAll != 0;
    if (!reached) {
        // A voxel outside the grid takes the nearest brick: within the reach of the grid it is
        // that brick's neighbour, further out its look-up reads nothing that changed.
        ivec3 voxel = ivec3(floor((pos.xyz - u_gridOrigin) / u_voxelSize));
        ivec3 b = clamp(voxel / u_brick, ivec3(0), ivec3(u_bricksPerAxis - 1));
        reached = b_reached[(b.z * u_bricksPerAxis + b.y) * u_bricksPerAxis + b.x] != 0u;
    }
    if (reached)
        b_lookup[atomicAdd(b_lookupCount, 1u)] = uint(xy.x) | (uint(xy.y) << 16);
    else
        listIfBehind(xy, imageLoad(u_accum, xy), false);
}
#else
void main() {
    uint i = lineGroup() * 64u + gl_LocalInvocationIndex;  // gpu::dispatchLine
    if (i >= b_lookupCount) return;
    ivec2 xy = ivec2(int(b_lookup[i] & 0xffffu), int(b_lookup[i] >> 16));
    vec4 pos = texelFetch(u_position, xy, 0);
    vec4 normalId = texelFetch(u_normal, xy, 0);
    vec3 sigT = vec3(0.0), sigS = vec3(0.0);
    if (u_hasMaterial != 0)
        dipoleMaterialInside(u_volumeSigmaT, u_volumeSigmaS, u_gridOrigin, u_voxelSize,
                             u_resolution, pos.xyz, normalize(normalId.xyz), sigT, sigS);
    vec4 acc = imageLoad(u_accum, xy);
    bool restarted = false;
    if (imageLoad(u_sigmaT, xy).rgb != sigT || imageLoad(u_sigmaS, xy).rgb != sigS) {
        float R = discRadius(u_model, sigT, sigS, u_boundary, u_discQuantile, u_maxRadius);
        imageStore(u_sigmaT, xy, vec4(sigT, 0.0));
        imageStore(u_sigmaS, xy, vec4(sigS, R));
        acc = vec4(0.0);
        imageStore(u_accum, xy, acc);
        atomicAdd(b_restarted, 1u);
        restarted = true;
        if (R > 0.0) {
            atomicMin(b_minRadius, floatBitsToUint(R));
            atomicMax(b_maxRadius, floatBitsToUint(R));
        }
    }
    listIfBehind(xy, acc, restarted);
}
#endif
