#version 450 core
// SPDX-License-Identifier: MIT
// One SSLPV propagation step (Børlum et al. 2011, §3.2 and §4), GLSL port of the CPU kernel in
// engine/src/sslpv/SslpvSolver.cpp: gather c_d,i = Σ_o Σ_j M_o[i][j] c_{d+o,j} from the six
// neighbours (matrices computed on the CPU by quadrature, passed as a term list), then sinks
// (exitant flux removal), accumulation and the next step's folded per-cell factors
// a·((1 − s′) + s′g^l) (§3.2.1, Eq. 3). Grids are SoA planes [channel][coefficient][cell] with a
// one-cell zero border, x fastest; SSLPV_FP16 stores them as packed half pairs.
// One invocation per pair of consecutive cells (so fp16 pairs are written by one invocation)
// and per colour channel (gl_GlobalInvocationID.y).

#include "common/dispatch.glsl"

layout(local_size_x = 64) in;

#ifdef SSLPV_FP16
#define CELL uint
#define LOAD(buf, i) (unpackHalf2x16(buf[(i) >> 1])[(i) & 1])
#define STORE_PAIR(buf, e, a, b) buf[(e) >> 1] = packHalf2x16(vec2(a, b))
#else
#define CELL float
#define LOAD(buf, i) (buf[i])
#define STORE_PAIR(buf, e, a, b) \
    buf[e] = (a);                \
    buf[(e) + 1] = (b)
#endif

layout(std430, binding = 0) readonly buffer SrcBlock { CELL b_src[]; };
layout(std430, binding = 1) writeonly buffer DstBlock { CELL b_dst[]; };
layout(std430, binding = 2) buffer AccBlock { CELL b_acc[]; };
layout(std430, binding = 3) buffer ExitBlock { CELL b_exit[]; };
layout(std430, binding = 4) readonly buffer FactorBlock { float b_factor[]; };  // [ch*3+band]
layout(std430, binding = 5) readonly buffer MaskBlock { float b_mask[]; };
// x: source coefficient, y: padded linear offset of the source cell, z: weight bits.
layout(std430, binding = 6) readonly buffer TermBlock { ivec4 b_terms[]; };

uniform int u_planeSize;      // floats per plane on the GPU (even)
uniform int u_cells;          // (N+2)³ real cells per plane
uniform int u_padded;         // N+2
uniform int u_coeffs;         // 4 or 9
uniform int u_termStart[10];  // term list of coefficient i: [u_termStart[i], u_termStart[i+1])
uniform int u_accumulate;     // add this step to the accumulation grid
uniform int u_assignAcc;      // first accumulated step: acc = c
uniform int u_sinks;          // exitant removal on
uniform int u_assignExit;     // first step: exit = leave
#ifdef SSLPV_L1
uniform vec4 u_l1[6];   // per neighbour (+x, −x, +y, −y, +z, −z): w00, w0k, wk0, wkk
uniform vec2 u_l1d[6];  // the other two dipole coefficients' diagonal weights
uniform int u_offset[6];
#endif

int bandOf(int i) { return i == 0 ? 0 : (i < 4 ? 1 : 2); }

void main() {
    int e = int(lineGroup() * 64u + gl_LocalInvocationID.x) * 2;  // gpu::dispatchLine
    int ch = int(gl_GlobalInvocationID.y);
    if (e >= u_planeSize || ch >= 3) return;
    bool interior[2];
    for (int h = 0; h < 2; ++h) {
        int cell = e + h;
        int x = cell % u_padded, y = (cell / u_padded) % u_padded;
        int z = cell / (u_padded * u_padded);
        interior[h] = cell < u_cells && x >= 1 && y >= 1 && z >= 1 && x < u_padded - 1 &&
                      y < u_padded - 1 && z < u_padded - 1;
    }
#ifdef SSLPV_L1
    // Order 1: the matrices' sparsity (§4) with the weights in uniforms, all four outputs at
    // once; a neighbour along the axis with dipole coefficient k couples c00 and c_k and scales
    // the other two (u_l1[nb] = w00, w0k, wk0, wkk; u_l1d[nb] = the two diagonal weights).
    float g[2][4];
    for (int h = 0; h < 2; ++h) {
        for (int c = 0; c < 4; ++c) g[h][c] = 0.0;
        if (!interior[h]) continue;
        for (int nb = 0; nb < 6; ++nb) {
            int k = nb < 2 ? 3 : (nb < 4 ? 1 : 2);
            int a = k == 1 ? 2 : 1;
            int b = k == 3 ? 2 : 3;
            int at = e + h + u_offset[nb];
            float s0 = LOAD(b_src, (ch * 4) * u_planeSize + at);
            float sk = LOAD(b_src, (ch * 4 + k) * u_planeSize + at);
            float sa = LOAD(b_src, (ch * 4 + a) * u_planeSize + at);
            float sb = LOAD(b_src, (ch * 4 + b) * u_planeSize + at);
            g[h][0] += u_l1[nb].x * s0 + u_l1[nb].y * sk;
            g[h][k] += u_l1[nb].z * s0 + u_l1[nb].w * sk;
            g[h][a] += u_l1d[nb].x * sa;
            g[h][b] += u_l1d[nb].y * sb;
        }
    }
#endif
    for (int i = 0; i < u_coeffs; ++i) {
        float o[2] = float[2](0.0, 0.0);
#ifdef SSLPV_L1
        o[0] = g[0][i];
        o[1] = g[1][i];
#else
        for (int h = 0; h < 2; ++h) {
            if (!interior[h]) continue;
            float sum = 0.0;
            for (int t = u_termStart[i]; t < u_termStart[i + 1]; ++t) {
                ivec4 term = b_terms[t];
                sum += intBitsToFloat(term.z) *
                       LOAD(b_src, (ch * u_coeffs + term.x) * u_planeSize + e + h + term.y);
            }
            o[h] = sum;
        }
#endif
        int base = (ch * u_coeffs + i) * u_planeSize + e;
        if (u_sinks != 0) {
            // Sinks: flux reaching a cell outside the object leaves it (recorded, removed).
            float leave[2];
            for (int h = 0; h < 2; ++h) {
                float m = b_mask[e + h];
                leave[h] = o[h] * (1.0 - m);
                o[h] *= m;
                if (u_assignExit == 0) leave[h] += LOAD(b_exit, base + h);
            }
            STORE_PAIR(b_exit, base, leave[0], leave[1]);
        }
        if (u_accumulate != 0) {
            float a0 = o[0], a1 = o[1];
            if (u_assignAcc == 0) {
                a0 += LOAD(b_acc, base);
                a1 += LOAD(b_acc, base + 1);
            }
            STORE_PAIR(b_acc, base, a0, a1);
        }
        int f = (ch * 3 + bandOf(i)) * u_planeSize + e;
        STORE_PAIR(b_dst, base, o[0] * b_factor[f], o[1] * b_factor[f + 1]);
    }
}
