// SPDX-License-Identifier: MIT
// Shared by the dipole::DirpoleSubsurfaceProvider passes (dirpole_gather.comp,
// dirpole_combine.comp): the six orthographic cube-face cameras and the painted material.
#pragma once

// Cube faces +x −x +y −y +z −z: face f's camera sits on the +axis side and looks along −axis.
layout(location = 20) uniform mat4 u_faceClipFromWorld[6];

// Painted material: rgb σt (mm⁻¹) and a = inside in u_volumeSigmaT, rgb σs′ in u_volumeSigmaS.
layout(binding = 6) uniform sampler3D u_volumeSigmaT;
layout(binding = 7) uniform sampler3D u_volumeSigmaS;
uniform int u_hasMaterial;
uniform vec3 u_gridOrigin;  // mm, corner of voxel (0,0,0)
uniform float u_voxelSize;  // mm
uniform int u_resolution;

// σt and σs′ just inside the surface at p with outward normal n: the first non-empty voxel
// among p − k·(voxel/2)·n, k = 1..6 (the surface lookup of dipole::buildSurfaceBuffers).
// Returns false when there is no material there (black).
bool materialInside(vec3 p, vec3 n, out vec3 sigT, out vec3 sigS) {
    sigT = vec3(0.0);
    sigS = vec3(0.0);
    if (u_hasMaterial == 0) return false;
    for (int k = 1; k <= 6; ++k) {
        ivec3 c = ivec3(floor((p - (0.5 * float(k) * u_voxelSize) * n - u_gridOrigin) / u_voxelSize));
        if (any(lessThan(c, ivec3(0))) || any(greaterThanEqual(c, ivec3(u_resolution)))) continue;
        vec4 t = texelFetch(u_volumeSigmaT, c, 0);
        if (t.rgb == vec3(0.0)) continue;
        sigT = t.rgb;
        sigS = texelFetch(u_volumeSigmaS, c, 0).rgb;
        return true;
    }
    return false;
}
