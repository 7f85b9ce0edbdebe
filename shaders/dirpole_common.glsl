// SPDX-License-Identifier: MIT
// Shared by the dipole::DirpoleSubsurfaceProvider passes (dirpole_gather.comp,
// dirpole_combine.comp): the six orthographic cube-face cameras and the painted material.
#pragma once
#include "dipole_material.glsl"

// Cube faces +x −x +y −y +z −z: face f's camera sits on the +axis side and looks along −axis.
layout(location = 20) uniform mat4 u_faceClipFromWorld[6];

// Frame statistics (one SSBO, cleared by the CPU before each frame; the C++ side reads the eight
// words back): the gather's convergence words (float bits; non-negative floats order like their
// bit patterns) and sampled-texel count, the prepare pass's counts (dirpole_prepare.comp).
layout(std430, binding = 4) buffer DirpoleFrameStats {
    uint b_maxChange;  // max over sampled texels of |mean after − mean before| (float bits)
    uint b_maxMean;    // max over sampled texels of the mean after (float bits)
    uint b_sampled;    // texels that got samples
    uint b_covered;    // covered texels
    uint b_restarted;  // texels restarted because their material changed
    uint b_listed;     // texels in the gather's work list (dirpole_compact.comp)
    uint b_minN;       // fewest samples of a covered texel (after the restarts)
    uint b_maxN;       // most samples of a covered texel
};

// Face texel lists (dirpole_compact.comp): x | y << 12 | face << 24 (cubeMapSize ≤ 4096).
uint packTexel(ivec3 id) { return uint(id.x) | (uint(id.y) << 12) | (uint(id.z) << 24); }
ivec3 unpackTexel(uint e) { return ivec3(e & 0xfffu, (e >> 12) & 0xfffu, e >> 24); }

// Painted material: rgb σt (mm⁻¹) and a = inside in u_volumeSigmaT, rgb σs′ in u_volumeSigmaS.
layout(binding = 6) uniform sampler3D u_volumeSigmaT;
layout(binding = 7) uniform sampler3D u_volumeSigmaS;
uniform int u_hasMaterial;
uniform vec3 u_gridOrigin;  // mm, corner of voxel (0,0,0)
uniform float u_voxelSize;  // mm
uniform int u_resolution;

// σt and σs′ just inside the surface at p with outward normal n (dipole_material.glsl: the
// surface lookup of dipole::buildSurfaceBuffers). Returns false when there is no material
// there (black).
bool materialInside(vec3 p, vec3 n, out vec3 sigT, out vec3 sigS) {
    sigT = vec3(0.0);
    sigS = vec3(0.0);
    if (u_hasMaterial == 0) return false;
    return dipoleMaterialInside(u_volumeSigmaT, u_volumeSigmaS, u_gridOrigin, u_voxelSize,
                                u_resolution, p, n, sigT, sigS);
}
