#version 450 core
// SPDX-License-Identifier: MIT
// SSLPV per-pixel sample pass of SslpvSubsurfaceProvider (Børlum et al. 2011, Børlum et al. 2011, §3.3):
// at every covered G-buffer pixel, the exitant radiance estimate of the CPU SslpvRenderer
// (engine/src/sslpv/SslpvRenderer.cpp + SslpvSolver::radiance), line for line:
//   L_i = (2/A)(c00·Y00 + ½·K1·c10^(n)),  A = Δx²,  c10^(n) = n·(c11, c1−1, c10)   (Eq. 5–7)
//   L_o = S·(1 − F_r(cos θ_o, η))·max(0, L_i)                                     (Eq. 4/7)
// S = SslpvSolver::exitScale(): 1/η² in Paper mode, gain/η² in Calibrated mode.
// with the coefficients read at p − d·Δx·n, d = ½, 1, 3⁄2 (first depth whose inside weight
// exceeds 1e-4), trilinear over the 8 nearest cell centres that are inside, renormalised; a part
// thinner than half a cell, with no inside cell, from its neighbours (radianceThin, THIN_PASS).
// Only bands 0 and 1 are read: band 2's hemisphere integral vanishes (Eq. 7).
// Mode diffusion (DIFFUSION=1): band 0 only; its band-1 slot holds each cell's reduced albedo
// (shared/SslpvShared.h), read with the same weights, and with u_exitCorrection the light
// leaves with the exact half-space's exit-angle distribution c(α′, cos θ_o)
// (SslpvSolver::exitantRadiance). With u_surfaceFlux, slots 2–4 hold the flux along the surface
// J_t (x, y, z per channel) and the light leaving along the refracted direction ω also carries
// P1's flux term: × max(0, 1 + 3 J_t·ω_t/(J(2A + 3μ))).

// Compiled twice (SslpvSubsurfaceProvider): DIFFUSION=1 for mode diffusion, with its albedo, exit
// table and surface flux; without it for the propagation modes, which then carry none of that
// code (llvmpipe ran it under the execution mask: the pass took 9.8 instead of 7.3 ms at
// 640×360).
#ifndef DIFFUSION
#define DIFFUSION 0
#endif
// ALBEDO_OUT=1 (mode diffusion only; a third program): the albedo the read-out sees is also
// written to u_albedoOut (SslpvSolver::readoutAlbedo; 0 where no cell is read), for the
// combined method's local kernel (SslpvSubsurfaceProvider::setAlbedoOutput).
#ifndef ALBEDO_OUT
#define ALBEDO_OUT 0
#endif
#if ALBEDO_OUT && !DIFFUSION
#error "ALBEDO_OUT needs DIFFUSION: the propagation modes hold no albedo"
#endif
// THIN_PASS=1: the second dispatch, over the pixels the first appended to the thin-part list
// (shared/SslpvShared.h, LUCENT_SSLPV_BINDING_THIN_PIXELS), which it shades with the thin-part
// read-out; the first pass (THIN_PASS=0) carries none of that code. Each pass writes only its
// own pixels, so together they write the one pass's image (measured: docs/benchmarks.md).
#ifndef THIN_PASS
#define THIN_PASS 0
#endif

#include "shared/SslpvShared.h"

#if THIN_PASS
layout(local_size_x = LUCENT_SSLPV_THIN_PASS_GROUP_SIZE) in;
#else
layout(local_size_x = 8, local_size_y = 8) in;
#endif

layout(binding = 0) uniform sampler2D u_position;  // world position (mm), a = coverage
layout(binding = 1) uniform sampler2D u_normal;    // unit normal facing the camera, a = id + 1
layout(binding = 2) uniform sampler3D u_c0;  // rgb: coefficient Y00 per channel, a: read-out alpha
layout(binding = 3) uniform sampler3D u_c1;  // rgb: Y1-1
layout(binding = 4) uniform sampler3D u_c2;  // rgb: Y10
layout(binding = 5) uniform sampler3D u_c3;  // rgb: Y11
layout(binding = 6) uniform sampler3D u_c4;  // rgb: Y2-2 (mode diffusion only: surface flux z)

layout(rgba32f, binding = 0) writeonly uniform image2D u_target;  // W/(mm²·sr)
#if ALBEDO_OUT
layout(rgba32f, binding = 1) writeonly uniform image2D u_albedoOut;  // rgb: α′ read, a: 1
#endif

layout(std430, binding = LUCENT_SSLPV_BINDING_THIN_PIXELS) buffer ThinPixels {
    uint b_thinGroups[3];  // glDispatchComputeIndirect's arguments for the thin pass
    uint b_thinCount;
    uint b_thinPixels[];   // x | y << 16
};

#if LUCENT_SSLPV_DIFFUSION_ALBEDO_COEFF != 1 || LUCENT_SSLPV_DIFFUSION_FLUX_COEFF != 2
#error "radianceInside reads the albedo from u_c1 and the surface flux from u_c2, u_c3, u_c4"
#endif
#define LUCENT_EXIT_TABLE_BINDING LUCENT_SSLPV_BINDING_EXIT_TABLE
#include "common/exit_table.glsl"

uniform mat4 u_objectFromWorld;  // rigid: rest space of the object
uniform vec3 u_eye;              // camera position, world (perspective)
uniform vec3 u_forward;          // camera forward, world (orthographic)
uniform int u_ortho;
uniform ivec2 u_size;
uniform int u_meshId;      // −1: every covered pixel
uniform vec3 u_origin;     // LPV grid origin (rest space, mm)
uniform float u_h;         // LPV cell size Δx, mm
uniform int u_res;         // LPV cells per axis
uniform float u_eta;       // relative index of refraction
uniform float u_exitScale; // SslpvSolver::exitScale()
uniform float u_Y00;       // 1/(2√π)
uniform float u_K1;        // √(3/(4π))
uniform int u_exitCorrection; // mode diffusion: apply exitCorrection (table bound)
uniform int u_surfaceFlux;    // mode diffusion: apply the surface flux's P1 term
uniform float u_twoA;         // 2A, the Robin condition's constant (GridDiffusion)

// Exact unpolarised Fresnel reflectance (Born & Wolf §1.5), as lucent::sslpv::dielectricReflectance.
float dielectricReflectance(float cosThetaI, float eta) {
    cosThetaI = clamp(cosThetaI, 0.0, 1.0);
    if (!(eta > 0.0)) return 1.0;
    float sin2T = (1.0 - cosThetaI * cosThetaI) / (eta * eta);
    if (sin2T >= 1.0) return 1.0;
    float cosT = sqrt(1.0 - sin2T);
    float rParl = (eta * cosThetaI - cosT) / (eta * cosThetaI + cosT);
    float rPerp = (cosThetaI - eta * cosT) / (cosThetaI + eta * cosT);
    return clamp(0.5 * (rParl * rParl + rPerp * rPerp), 0.0, 1.0);
}

// The coefficients of cell `cell` times w, added to c0…c4 (c4: mode diffusion's surface flux z).
void addCell(ivec3 cell, vec4 t0, float w, inout vec3 c0, inout vec3 c1, inout vec3 c2,
             inout vec3 c3, inout vec3 c4) {
    c0 += w * t0.rgb;
    c1 += w * texelFetch(u_c1, cell, 0).rgb;
    c2 += w * texelFetch(u_c2, cell, 0).rgb;
    c3 += w * texelFetch(u_c3, cell, 0).rgb;
#if DIFFUSION
    if (u_surfaceFlux != 0) c4 += w * texelFetch(u_c4, cell, 0).rgb;
#endif
}

// L_i from the summed coefficients: divided by their weight sum, the light's coefficients also
// multiplied by `scale` (the thin-part read's thickness; mode diffusion's albedo is not light).
vec3 radianceFrom(vec3 c0, vec3 c1, vec3 c2, vec3 c3, vec3 c4, float wsum, float scale, vec3 n,
                  out vec3 albedo, out vec3 jt[3]) {
    float light = scale / wsum;
    float invA = 1.0 / (u_h * u_h);
#if DIFFUSION
    // Per channel k: J_t = (x, y, z) from slots 2, 3, 4 (rgb = the channels).
    for (int k = 0; k < 3; ++k) jt[k] = light * vec3(c2[k], c3[k], c4[k]);
    albedo = c1 / wsum;  // the LUCENT_SSLPV_DIFFUSION_ALBEDO_COEFF slot
    return max(vec3(0.0), 2.0 * invA * (u_Y00 * light * c0));
#else
    vec3 c10n = n.x * c3 + n.y * c1 + n.z * c2;
    return max(vec3(0.0), 2.0 * invA * light * (u_Y00 * c0 + 0.5 * u_K1 * c10n));
#endif
}

bool inGrid(ivec3 cell) {
    return all(greaterThanEqual(cell, ivec3(0))) && all(lessThan(cell, ivec3(u_res)));
}

void clearReadout(out vec3 albedo, out vec3 jt[3]) {
    albedo = vec3(0.0);
    jt[0] = vec3(0.0);
    jt[1] = vec3(0.0);
    jt[2] = vec3(0.0);
}

#if !THIN_PASS
// False when none of the three depths finds a readable cell: a part thinner than half a cell,
// left to the thin pass.
bool radianceInside(vec3 p, vec3 n, out vec3 Li, out vec3 albedo, out vec3 jt[3]) {
    clearReadout(albedo, jt);
    Li = vec3(0.0);
    const float depths[3] = float[3](0.5, 1.0, 1.5);
    for (int d = 0; d < 3; ++d) {
        vec3 u = (p - depths[d] * u_h * n - u_origin) / u_h - vec3(0.5);
        ivec3 i0 = ivec3(floor(u));
        vec3 f = u - vec3(i0);
        float wsum = 0.0;
        vec3 c0 = vec3(0.0), c1 = vec3(0.0), c2 = vec3(0.0), c3 = vec3(0.0), c4 = vec3(0.0);
        for (int corner = 0; corner < 8; ++corner) {
            ivec3 o = ivec3(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            ivec3 cell = i0 + o;
            if (!inGrid(cell)) continue;
            // The readable flag and c00 in one fetch (a fetch each made the pass 5 % slower).
            vec4 t0 = texelFetch(u_c0, cell, 0);
            if (t0.a <= LUCENT_SSLPV_READABLE_ALPHA_MIN) continue;
            float w = (o.x != 0 ? f.x : 1.0 - f.x) * (o.y != 0 ? f.y : 1.0 - f.y) *
                      (o.z != 0 ? f.z : 1.0 - f.z);
            if (w <= 0.0) continue;
            wsum += w;
            addCell(cell, t0, w, c0, c1, c2, c3, c4);
        }
        if (wsum > 1e-4) {
            Li = radianceFrom(c0, c1, c2, c3, c4, wsum, 1.0, n, albedo, jt);
            return true;
        }
    }
    return false;
}
#else
// A part thinner than half a cell (SslpvSolver::thinPartCoefficients, line for line): the
// readable cells within LUCENT_SSLPV_THIN_PART_REACH cells of the depth-½ point, Gaussian
// in distance (cells), scaled by 2f, f the largest alpha (the inside fraction, capped at ½)
// of the eight cells around that point.
vec3 radianceThin(vec3 p, vec3 n, out vec3 albedo, out vec3 jt[3]) {
    clearReadout(albedo, jt);
    vec3 u = (p - 0.5 * u_h * n - u_origin) / u_h - vec3(0.5);
    ivec3 i0 = ivec3(floor(u));
    float fraction = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
        ivec3 cell = i0 + ivec3(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        if (inGrid(cell)) fraction = max(fraction, min(texelFetch(u_c0, cell, 0).a, 0.5));
    }
    if (!(fraction > 0.0)) return vec3(0.0);
    ivec3 centre = ivec3(floor(u + vec3(0.5)));
    float wsum = 0.0;
    vec3 c0 = vec3(0.0), c1 = vec3(0.0), c2 = vec3(0.0), c3 = vec3(0.0), c4 = vec3(0.0);
    const int R = LUCENT_SSLPV_THIN_PART_REACH, W = 2 * R + 1;
    for (int k = 0; k < W * W * W; ++k) {
        ivec3 cell = centre + ivec3(k % W, (k / W) % W, k / (W * W)) - ivec3(R);
        if (!inGrid(cell)) continue;
        vec4 t0 = texelFetch(u_c0, cell, 0);
        if (t0.a <= LUCENT_SSLPV_READABLE_ALPHA_MIN) continue;
        vec3 d = u - vec3(cell);
        float w = exp(-dot(d, d));
        wsum += w;
        addCell(cell, t0, w, c0, c1, c2, c3, c4);
    }
    if (!(wsum > 1e-6)) return vec3(0.0);
    return radianceFrom(c0, c1, c2, c3, c4, wsum, 2.0 * fraction, n, albedo, jt);
}
#endif

void shadePixel(ivec2 px) {
    vec4 pos = texelFetch(u_position, px, 0);
    vec4 nrm = texelFetch(u_normal, px, 0);
    vec3 L = vec3(0.0);
    vec3 albedoRead = vec3(0.0);
    bool mine = u_meshId < 0 || int(nrm.a + 0.5) == u_meshId + 1;
    if (pos.a > 0.5 && mine) {
        vec3 wo = u_ortho != 0 ? -normalize(u_forward) : normalize(u_eye - pos.xyz);
        vec3 nw = normalize(nrm.xyz);
        float cosO = dot(nw, wo);
        if (cosO > 0.0) {
            vec3 p = (u_objectFromWorld * vec4(pos.xyz, 1.0)).xyz;
            vec3 n = normalize(mat3(u_objectFromWorld) * nw);
            vec3 albedo;
            vec3 jt[3];
#if THIN_PASS
            vec3 Li = radianceThin(p, n, albedo, jt);
#else
            vec3 Li;
            if (!radianceInside(p, n, Li, albedo, jt)) {
                // The thin pass shades (and writes) this pixel; one more group per
                // LUCENT_SSLPV_THIN_PASS_GROUP_SIZE pixels.
                uint slot = atomicAdd(b_thinCount, 1u);
                b_thinPixels[slot] = uint(px.x) | (uint(px.y) << 16);
                uint group = slot / uint(LUCENT_SSLPV_THIN_PASS_GROUP_SIZE);
                if (slot % uint(LUCENT_SSLPV_THIN_PASS_GROUP_SIZE) == 0u &&
                    group < uint(LUCENT_SSLPV_THIN_PASS_MAX_GROUPS))
                    atomicAdd(b_thinGroups[0], 1u);
                return;
            }
#endif
            albedoRead = albedo;
            L = (u_exitScale * (1.0 - dielectricReflectance(cosO, u_eta))) * Li;
#if DIFFUSION
            if (u_exitCorrection != 0)
                for (int c = 0; c < 3; ++c)
                    if (albedo[c] > 0.0) L[c] *= exitCorrection(albedo[c], cosO);
            if (u_surfaceFlux != 0) {
                // Object space, as the grid: the refracted direction's tangential part and cosine.
                vec3 woObj = normalize(mat3(u_objectFromWorld) * wo);
                float cosObj = dot(n, woObj);
                vec3 wt = (woObj - cosObj * n) / u_eta;
                float mu = sqrt(max(0.0, 1.0 - dot(wt, wt)));
                // Li = 2/(Δx²)·Y00·c00 is proportional to J; the ratio needs c00 itself.
                vec3 jn = Li * (u_h * u_h) / (2.0 * u_Y00);
                // |J| ≤ φ: J_t limited to J_n·√(4A² − 1), as the CPU read-out.
                float limit = sqrt(max(0.0, u_twoA * u_twoA - 1.0));
                for (int c = 0; c < 3; ++c)
                    if (jn[c] > 0.0) {
                        vec3 j = jt[c];
                        float size = length(j);
                        if (size > limit * jn[c]) j *= limit * jn[c] / size;
                        L[c] *= max(0.0, 1.0 + 3.0 * dot(j, wt) / (jn[c] * (u_twoA + 3.0 * mu)));
                    }
            }
#endif
        }
    }
    imageStore(u_target, px, vec4(L, 1.0));
#if ALBEDO_OUT
    imageStore(u_albedoOut, px, vec4(albedoRead, 1.0));
#endif
}

void main() {
#if THIN_PASS
    // Beyond LUCENT_SSLPV_THIN_PASS_MAX_GROUPS groups each invocation takes every stride-th pixel.
    uint stride = gl_NumWorkGroups.x * uint(LUCENT_SSLPV_THIN_PASS_GROUP_SIZE);
    for (uint i = gl_GlobalInvocationID.x; i < b_thinCount; i += stride) {
        uint packedPx = b_thinPixels[i];
        shadePixel(ivec2(packedPx & 0xffffu, packedPx >> 16));
    }
#else
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x < u_size.x && px.y < u_size.y) shadePixel(px);
#endif
}
