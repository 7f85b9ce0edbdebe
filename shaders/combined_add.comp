#version 450 core
// SPDX-License-Identifier: MIT
// Combined subsurface mode (docs/methods/combined.md), the last pass of
// lucent::combined::CombinedSubsurfaceProvider: the SSLPV term (Borlum et al. 2011, Børlum et al. 2011,
// Eq. 4/7) is already in the target, the windowed image-space dipole term (Mertens et al. 2005,
// Mertens et al. 2005, Eq. 3 restricted to r <= r_s) is in u_addend. Steps split: target += addend.
// Kernel split: SSLPV's own local part is removed as well,
//   L(x_o) = max(0, L_sslpv + L_dipole,r<=r_s - min(Lhat, f L_sslpv)),
//   Lhat = F_t(eta, w_o)/pi B_near,  f = B_near / (B_near + B_far),
//   B = (area / N) sum_i R_lpv(r_i) E(p_i)
// (uniform samples on the disc r <= r_s and on the annulus r_s < r <= outer ring), line for
// line as lucent::combined::localSslpvEstimate / localSslpvFraction (engine/src/combined/
// Combined.cpp). Two programs: with LOCAL_ESTIMATE, Lhat into u_local and f into u_fraction
// (they depend on the G-buffer, the irradiance image and the kernel, not on the painted
// material or the dipole's progress, so the provider computes them only when those change);
// without, the per-frame sum (Lhat and f read only in the Kernel split); with SURFACE_SCALE
// as well (the diffusion part on a painted volume), Lhat carried from the kernel's material to
// the one at x_o.

#include "dipole_fresnel.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

#ifdef LOCAL_ESTIMATE
layout(rgba32f, binding = 2) writeonly uniform image2D u_local;     // Lhat, a own pixel
layout(rgba32f, binding = 3) writeonly uniform image2D u_fraction;  // f (near share)
#else
layout(rgba32f, binding = 0) uniform image2D u_target;           // SSLPV term in, sum out
layout(rgba32f, binding = 1) readonly uniform image2D u_addend;  // the dipole term
layout(rgba32f, binding = 2) readonly uniform image2D u_local;     // Lhat (Kernel split)
layout(rgba32f, binding = 3) readonly uniform image2D u_fraction;  // f (Kernel split)
#ifdef SURFACE_SCALE
layout(rgba32f, binding = 4) readonly uniform image2D u_albedo;    // alpha' SSLPV reads
layout(rgba32f, binding = 5) readonly uniform image2D u_sigmaT;    // sigma_t' the dipole reads
layout(rgba32f, binding = 6) readonly uniform image2D u_sigmaS;    // sigma_s' the dipole reads
#endif
#endif

layout(binding = 0) uniform sampler2D u_position;    // xyz mm, a coverage
layout(binding = 1) uniform sampler2D u_normal;      // unit normal, a = mesh id + 1
layout(binding = 2) uniform sampler2D u_irradiance;  // Fresnel-transmitted E (W/mm^2)

// SSLPV surface kernel: ring b covers (outer_{b-1}, outer_b], value R_lpv rgb (mm^-2).
layout(std430, binding = 0) readonly buffer KernelBlock { vec4 b_ring[]; };  // outer, rgb

uniform ivec2 u_size;
uniform int u_kernel;  // 1: Kernel split (subtract), 0: Steps split (add only)
uniform int u_ringCount;
uniform float u_splitRadius;  // r_s, mm
uniform int u_samples;
uniform uint u_seed;
uniform int u_meshId;  // -1: every covered pixel
uniform mat4 u_clipFromWorld;
uniform vec3 u_eye;
uniform vec3 u_viewDir;
uniform int u_ortho;
uniform float u_eta;

const float PI = 3.14159265358979;

vec3 towardEye(vec3 p) { return u_ortho != 0 ? -normalize(u_viewDir) : normalize(u_eye - p); }

// Top-first pixel of p like SurfaceBuffers::project; false outside the image.
bool projectTop(vec3 p, out ivec2 top) {
    vec4 clip = u_clipFromWorld * vec4(p, 1.0);
    if (!(clip.w > 0.0)) return false;
    vec2 ndc = clip.xy / clip.w;
    vec2 px = vec2((ndc.x * 0.5 + 0.5) * float(u_size.x), (0.5 - ndc.y * 0.5) * float(u_size.y));
    if (px.x < 0.0 || px.y < 0.0 || px.x >= float(u_size.x) || px.y >= float(u_size.y))
        return false;
    top = ivec2(px);
    return true;
}

// lucent::combined::pixelShift: chained PCG hashes (Jarzynski & Olano 2020).
uint pcg(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}
vec2 pixelShift(int x, int y) {
    uint h1 = pcg(uint(x) + pcg(uint(y) + pcg(u_seed)));
    uint h2 = pcg(h1);
    return vec2(float(h1 >> 8u), float(h2 >> 8u)) * (1.0 / 16777216.0);
}
float radicalInverse2(uint i) { return float(bitfieldReverse(i)) * 2.3283064365386963e-10; }

vec3 kernelAt(float r) {
    for (int b = 0; b < u_ringCount; ++b)
        if (r <= b_ring[b].x) return b_ring[b].yzw;
    return vec3(0.0);
}

// lucent::Frame (Duff et al. 2017 basis): the tangents fs, ft of unit normal no.
void tangentFrame(vec3 no, out vec3 fs, out vec3 ft) {
    float sgn = no.z >= 0.0 ? 1.0 : -1.0;
    float aa = -1.0 / (sgn + no.z);
    float bb = no.x * no.y * aa;
    fs = vec3(1.0 + sgn * no.x * no.x * aa, sgn * bb, -sgn * no.x);
    ft = vec3(bb, sgn + no.y * no.y * aa, -no.y);
}

bool ownPixel(ivec2 xy) {
    vec4 q = texelFetch(u_position, xy, 0);
    if (q.w == 0.0) return false;
    return u_meshId < 0 || int(texelFetch(u_normal, xy, 0).a + 0.5) - 1 == u_meshId;
}

#ifdef LOCAL_ESTIMATE
void main() {
    const ivec2 xy = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(xy, u_size)))
        return;
    vec3 local = vec3(0.0), frac = vec3(0.0);
    bool own = ownPixel(xy);
    if (own) {
        vec3 xo = texelFetch(u_position, xy, 0).xyz;
        vec3 no = normalize(texelFetch(u_normal, xy, 0).xyz);
        vec3 fs, ft;
        tangentFrame(no, fs, ft);
        int yTop = u_size.y - 1 - xy.y;
        vec2 shift = pixelShift(xy.x, yTop);
        // lucent::combined::localSslpvFraction: near disc r <= r_s and far annulus
        // (r_s, outer] with the same stratified samples; f = near / (near + far).
        float outer = u_ringCount > 0 ? max(b_ring[u_ringCount - 1].x, u_splitRadius)
                                      : u_splitRadius;
        vec3 Bn = vec3(0.0), Bf = vec3(0.0);
        for (int i = 0; i < u_samples; ++i) {
            vec2 h = vec2((float(i) + 0.5) / float(u_samples), radicalInverse2(uint(i)));
            float u = fract(h.x + shift.x), v = fract(h.y + shift.y);
            float phi = 2.0 * PI * v;
            vec3 dir = cos(phi) * fs + sin(phi) * ft;
            float rn = u_splitRadius * sqrt(u);
            float rf = sqrt(u_splitRadius * u_splitRadius +
                            u * (outer * outer - u_splitRadius * u_splitRadius));
            ivec2 top;
            if (projectTop(xo + rn * dir, top)) {
                ivec2 pix = ivec2(top.x, u_size.y - 1 - top.y);
                if (ownPixel(pix)) Bn += kernelAt(rn) * texelFetch(u_irradiance, pix, 0).rgb;
            }
            if (outer > u_splitRadius && projectTop(xo + rf * dir, top)) {
                ivec2 pix = ivec2(top.x, u_size.y - 1 - top.y);
                if (ownPixel(pix)) Bf += kernelAt(rf) * texelFetch(u_irradiance, pix, 0).rgb;
            }
        }
        Bn *= PI * u_splitRadius * u_splitRadius / float(u_samples);
        Bf *= PI * (outer * outer - u_splitRadius * u_splitRadius) / float(u_samples);
        vec3 all = Bn + Bf;
        for (int c = 0; c < 3; ++c)
            frac[c] = all[c] > 0.0 ? clamp(Bn[c] / all[c], 0.0, 1.0) : 0.0;
        float cosO = max(0.0, dot(no, towardEye(xo)));
        float fto = 1.0 - dipoleFresnelReflectance(cosO, u_eta);
        local = Bn * (fto / PI);
    }
    imageStore(u_local, xy, vec4(local, own ? 1.0 : 0.0));
    imageStore(u_fraction, xy, vec4(frac, own ? 1.0 : 0.0));  // a: the pixel is the object's
}
#else
#ifdef SURFACE_SCALE
#include "shared/SslpvShared.h"
#include "shared/CombinedShared.h"

uniform vec3 u_kernelTotal;      // KernelSurfaceTerms::exactTotal
uniform vec3 u_kernelNearShare;  // KernelSurfaceTerms::nearShare
uniform float u_boundaryA;       // A = (1 + F_dr)/(1 - F_dr)
// The exact half-space's total at u_i = i/NODES, alpha' = 1 - u_i^2
// (lucent::sslpv::ExactReflectanceRatio::exactTotals).
uniform float u_exactTotal[LUCENT_SSLPV_EXACT_TOTAL_NODES + 1];

// ExactReflectanceRatio::exactTotal: linear in u = sqrt(1 - alpha').
float exactTotal(float albedo) {
    float u = sqrt(1.0 - clamp(albedo, 0.0, 1.0)) * float(LUCENT_SSLPV_EXACT_TOTAL_NODES);
    int i = min(int(u), LUCENT_SSLPV_EXACT_TOTAL_NODES - 1);
    float f = u - float(i);
    return (1.0 - f) * u_exactTotal[i] + f * u_exactTotal[i + 1];
}

// lucent::combined::dipoleNearShare: the classical dipole's (Jensen et al. 2001) share of its
// total diffuse reflectance within r_s (mm) of the entry point: its R_d integrated beyond r_s and
// in all, in closed form (Mertens et al. 2005 Eq. 6-7); sigmaT in mm^-1.
float dipoleNearShare(float sigmaT, float albedo) {
    if (!(sigmaT > 0.0)) return 0.0;
    float zr = 1.0 / sigmaT;
    float zv = zr + 4.0 * u_boundaryA / (3.0 * sigmaT);
    float s = sigmaT * sqrt(3.0 * max(0.0, 1.0 - albedo));
    float r = u_splitRadius;
    float dr = sqrt(r * r + zr * zr), dv = sqrt(r * r + zv * zv);
    float total = exp(-s * zr) + exp(-s * zv);
    float beyond = zr * exp(-s * dr) / dr + zv * exp(-s * dv) / dv;
    return total > 0.0 ? clamp(1.0 - beyond / total, 0.0, 1.0) : 0.0;
}

// lucent::combined::discMeanMaterial: sigma_t' and sigma_s' averaged over the object's pixels
// holding material at the same Hammersley points of the disc r <= r_s on the tangent plane at x_o.
void discMeanMaterial(ivec2 xy, out vec3 sigmaT, out vec3 sigmaS) {
    sigmaT = vec3(0.0);
    sigmaS = vec3(0.0);
    vec3 xo = texelFetch(u_position, xy, 0).xyz;
    vec3 fs, ft;
    tangentFrame(normalize(texelFetch(u_normal, xy, 0).xyz), fs, ft);
    const int samples = LUCENT_COMBINED_DISC_MEAN_SAMPLES;
    int count = 0;
    for (int i = 0; i < samples; ++i) {
        vec2 h = vec2((float(i) + 0.5) / float(samples), radicalInverse2(uint(i)));
        float r = u_splitRadius * sqrt(h.x), phi = 2.0 * PI * h.y;
        ivec2 top;
        if (!projectTop(xo + r * (cos(phi) * fs + sin(phi) * ft), top)) continue;
        ivec2 pix = ivec2(top.x, u_size.y - 1 - top.y);
        // The dipole's irradiance pass writes sigma_t' on the object's pixels only: a zero is
        // another object, the background or no material (and costs no G-buffer fetches).
        vec3 st = imageLoad(u_sigmaT, pix).rgb;
        if (st == vec3(0.0)) continue;
        sigmaT += st;
        sigmaS += imageLoad(u_sigmaS, pix).rgb;
        ++count;
    }
    if (count > 0) {
        sigmaT /= float(count);
        sigmaS /= float(count);
    }
}

// lucent::combined::localScaleToSurfaceMaterial: R_exact(alpha'(x_o)) / R_exact(alpha'_kernel)
// times the near shares' ratio per channel; 1 where the read-out saw no cell or the kernel's
// total vanishes, the totals' ratio alone where the disc has no sigma_t' or the kernel no near
// share.
vec3 localScaleToSurfaceMaterial(ivec2 xy) {
    vec3 albedo = imageLoad(u_albedo, xy).rgb;
    vec3 sigmaT, sigmaS;
    discMeanMaterial(xy, sigmaT, sigmaS);
    vec3 scale = vec3(1.0);
    for (int c = 0; c < 3; ++c) {
        if (!(albedo[c] > 0.0 && u_kernelTotal[c] > 0.0)) continue;
        scale[c] = exactTotal(albedo[c]) / u_kernelTotal[c];
        if (sigmaT[c] > 0.0 && u_kernelNearShare[c] > 0.0)
            scale[c] *=
                dipoleNearShare(sigmaT[c], sigmaS[c] / sigmaT[c]) / u_kernelNearShare[c];
    }
    return scale;
}
#endif

void main() {
    const ivec2 xy = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(xy, u_size)))
        return;
    const vec4 a = imageLoad(u_target, xy);
    const vec4 d = imageLoad(u_addend, xy);
    vec3 sum = a.rgb + d.rgb;
    if (u_kernel != 0) {
        vec4 local = imageLoad(u_local, xy);
        // SSLPV's local part: the kernel's estimate Lhat, but at most the near share f of
        // SSLPV's own radiance (docs/methods/combined.md, "The split's fix").
        vec3 frac = imageLoad(u_fraction, xy).rgb;
        // At the material at x_o (docs/methods/combined.md, "The kernel at the painted
        // surface").
        if (local.a != 0.0) {
            vec3 lhat = local.rgb;
#ifdef SURFACE_SCALE
            lhat *= localScaleToSurfaceMaterial(xy);
#endif
            sum = max(sum - min(lhat, frac * a.rgb), vec3(0.0));
        }
    }
    imageStore(u_target, xy, vec4(sum, max(a.a, d.a)));
}
#endif
