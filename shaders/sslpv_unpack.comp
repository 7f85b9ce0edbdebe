#version 450 core
// SPDX-License-Identifier: MIT
// SSLPV: copies the GPU accumulation grid (SslpvGlPropagator's SSBO, SoA planes
// [channel][coefficient][padded cell], fp32 or packed fp16) into the four RGBA32F N³ textures
// sampled by sslpv_sample.comp (SslpvSubsurfaceProvider): texture i holds SH coefficient i of
// the three channels in rgb (Børlum et al. 2011, §3.3, Eq. 5–7 read bands 0 and 1 only);
// texture 0's alpha is the read-out's (SslpvSolver::readoutAlpha). Replaces a read-back + CPU
// re-upload.

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

#ifdef SSLPV_FP16
#define CELL uint
#define LOAD(buf, i) (unpackHalf2x16(buf[(i) >> 1])[(i) & 1])
#else
#define CELL float
#define LOAD(buf, i) (buf[i])
#endif

layout(std430, binding = 0) readonly buffer AccBlock { CELL b_acc[]; };
layout(std430, binding = 1) readonly buffer ReadoutAlphaBlock { float b_readoutAlpha[]; };  // padded plane

layout(rgba32f, binding = 0) writeonly uniform image3D u_c0;
layout(rgba32f, binding = 1) writeonly uniform image3D u_c1;
layout(rgba32f, binding = 2) writeonly uniform image3D u_c2;
layout(rgba32f, binding = 3) writeonly uniform image3D u_c3;

uniform int u_res;        // N
uniform int u_padded;     // N + 2
uniform int u_planeSize;  // cells per plane on the GPU (even)
uniform int u_coeffs;     // 4 or 9

vec3 coefficient(int i, int k) {
    return vec3(LOAD(b_acc, (0 * u_coeffs + i) * u_planeSize + k),
                LOAD(b_acc, (1 * u_coeffs + i) * u_planeSize + k),
                LOAD(b_acc, (2 * u_coeffs + i) * u_planeSize + k));
}

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(c, ivec3(u_res)))) return;
    int k = ((c.z + 1) * u_padded + c.y + 1) * u_padded + c.x + 1;
    imageStore(u_c0, c, vec4(coefficient(0, k), b_readoutAlpha[k]));
    imageStore(u_c1, c, vec4(coefficient(1, k), 0.0));
    imageStore(u_c2, c, vec4(coefficient(2, k), 0.0));
    imageStore(u_c3, c, vec4(coefficient(3, k), 0.0));
}
