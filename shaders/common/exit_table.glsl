// SPDX-License-Identifier: MIT
// The exact half-space's exit-angle correction c(α′, t) (lucent::dipole::DirpoleExitTable: the
// half-space's radiance leaving at outside cosine t over a Fresnel-weighted diffuse exit's, at
// reduced albedo α′), read from a shader-storage buffer of its nodes, row-major [albedo node]
// [cosine node] (shared/DirpoleShared.h). The includer defines LUCENT_EXIT_TABLE_BINDING, the
// buffer's binding point.
#pragma once
#include "shared/DirpoleShared.h"

layout(std430, binding = LUCENT_EXIT_TABLE_BINDING) readonly buffer ExitTableValues {
    float b_exit[];
};

// c(α′, t), bilinear between the nodes (uniform in s = √(1 − α′) and in t) as
// DirpoleExitTable::correction.
float exitCorrection(float alphaP, float t) {
    const int A = LUCENT_DIRPOLE_EXIT_ALBEDO_NODES, C = LUCENT_DIRPOLE_EXIT_COSINE_NODES;
    float s = sqrt(clamp(1.0 - alphaP, 0.0, 1.0)) * float(A - 1);
    int i = min(int(s), A - 2);
    float fs = s - float(i);
    float u = clamp(t, 0.0, 1.0) * float(C - 1);
    int j = min(int(u), C - 2);
    float fu = u - float(j);
    float lo = mix(b_exit[i * C + j], b_exit[i * C + j + 1], fu);
    float hi = mix(b_exit[(i + 1) * C + j], b_exit[(i + 1) * C + j + 1], fu);
    return mix(lo, hi, fs);
}
