// SPDX-License-Identifier: MIT
// The painted material just inside a surface point, for the dipole providers (the image-space
// dipole's irradiance pass and the directional dipole's face texels); the same rule as the CPU
// surface buffers (dipole::materialInside, engine/src/dipole/IrradiancePass.cpp):
//  1. the first non-empty voxel among p − k·(h/2)·n, k = 1..6 (voxels cut by the surface may be
//     masked out: their centre lies outside the mesh);
//  2. else the nearest non-empty voxel (cell centre distance) in the first shell of Chebyshev
//     radius 1..4 around the voxel of p − (h/2)·n that holds one. A mask with a hole under the
//     surface (a solid voxelisation where two closed parts overlap: Suzanne's eyes in her head)
//     otherwise left those pixels without material: black in the dipoles.
// σt in `volumeSigmaT`.rgb (0 where masked), σs′ in `volumeSigmaS`.rgb; h = voxelSize (mm).
// Returns false (σ = 0: black) when neither finds material.
#pragma once
// Its reach (how far from p's voxel it reads): LUCENT_DIPOLE_MATERIAL_REACH in shared/DipoleShared.h.

bool dipoleMaterialInside(sampler3D volumeSigmaT, sampler3D volumeSigmaS, vec3 gridOrigin,
                          float voxelSize, int resolution, vec3 p, vec3 n, out vec3 sigT,
                          out vec3 sigS) {
    sigT = vec3(0.0);
    sigS = vec3(0.0);
    for (int k = 1; k <= 6; ++k) {
        ivec3 c = ivec3(floor((p - (0.5 * float(k) * voxelSize) * n - gridOrigin) / voxelSize));
        if (any(lessThan(c, ivec3(0))) || any(greaterThanEqual(c, ivec3(resolution)))) continue;
        vec3 t = texelFetch(volumeSigmaT, c, 0).rgb;
        if (t == vec3(0.0)) continue;
        sigT = t;
        sigS = texelFetch(volumeSigmaS, c, 0).rgb;
        return true;
    }
    vec3 q = (p - 0.5 * voxelSize * n - gridOrigin) / voxelSize;  // in voxels
    ivec3 c0 = ivec3(floor(q));
    for (int r = 1; r <= 4; ++r) {
        float best = 1e30;
        for (int dz = -r; dz <= r; ++dz)
            for (int dy = -r; dy <= r; ++dy)
                for (int dx = -r; dx <= r; ++dx) {
                    ivec3 d = ivec3(dx, dy, dz);
                    if (max(abs(dx), max(abs(dy), abs(dz))) != r) continue;  // the shell only
                    ivec3 c = c0 + d;
                    if (any(lessThan(c, ivec3(0))) || any(greaterThanEqual(c, ivec3(resolution))))
                        continue;
                    vec3 t = texelFetch(volumeSigmaT, c, 0).rgb;
                    if (t == vec3(0.0)) continue;
                    vec3 e = vec3(c) + 0.5 - q;
                    float d2 = dot(e, e);
                    if (d2 < best) {
                        best = d2;
                        sigT = t;
                        sigS = texelFetch(volumeSigmaS, c, 0).rgb;
                    }
                }
        if (best < 1e30) return true;
    }
    return false;
}
