#version 450 core
// SPDX-License-Identifier: MIT
// Progressive image-space dipole gather of dipole::DipoleSubsurfaceProvider (Mertens et al.
// 2005, seed 004 §4–6): the estimator of dipole_gather.comp / engine/src/dipole/ImageSpace.cpp
// (importance samples of R_d(r)·r per channel + uniform disc samples, multi-sample balance
// heuristic §6.1, Eq. 9 Jacobian, interleaved Cranley–Patterson shifts), reading the renderer's
// G-buffer and the irradiance pass's images (GL rows, bottom first; the interleave cell and the
// pixel projection use top-first rows like the CPU gather, so frame 0 equals gatherImageSpace()).
// Each frame adds one estimate B_f (a new shift table) to a running sum; the output is the mean:
//   L = F_t(η, ω_o) · (Σ_f B_f / N) / π   (Eq. 3), W/(mm²·sr).
// Convergence statistics: atomic max of |B̄_N − B̄_{N−1}| and of B̄_N over pixels and channels.
#include "dipole_profiles.glsl"
#include "dipole_fresnel.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2D u_position;    // xyz mm, a coverage
layout(binding = 1) uniform sampler2D u_normal;      // unit normal facing the camera
layout(binding = 2) uniform sampler2D u_irradiance;  // E (W/mm²)
layout(binding = 3) uniform sampler2D u_sigmaT;      // σt (mm⁻¹)
layout(binding = 4) uniform sampler2D u_sigmaS;      // rgb σs′ (mm⁻¹), a disc radius R′ (mm)

layout(rgba32f, binding = 0) uniform image2D u_accum;            // rgb Σ_f B_f (W/mm²)
layout(rgba32f, binding = 1) writeonly uniform image2D u_target;  // renderer's subsurface term

layout(std430, binding = 0) readonly buffer ShiftBlock { vec4 b_shift[]; };  // 2 per cell
layout(std430, binding = 1) buffer StatsBlock { uint b_maxChange; uint b_maxMean; };

uniform mat4 u_clipFromWorld;
uniform vec3 u_eye;
uniform vec3 u_viewDir;
uniform int u_ortho;
uniform ivec2 u_size;
uniform int u_model;  // 0 dipole, 1 better dipole
uniform vec3 u_boundary;  // F_dr, C1, C2
uniform float u_eta;
uniform int u_nImp;
uniform int u_nUni;
uniform int u_jacobian;
uniform float u_maxJacobian;
uniform int u_interleave;
uniform int u_gather;      // 1: add one frame of samples; 0: only resolve the stored mean
uniform int u_framesBefore;  // frames already in u_accum

const float PI = 3.14159265358979;

vec3 towardEye(vec3 p) { return u_ortho != 0 ? -normalize(u_viewDir) : normalize(u_eye - p); }

// Pixel (GL rows, bottom first) containing p, computed like SurfaceBuffers::project (top-first).
bool projectToPixel(vec3 p, out ivec2 pix) {
    vec4 clip = u_clipFromWorld * vec4(p, 1.0);
    if (!(clip.w > 0.0)) return false;
    vec2 ndc = clip.xy / clip.w;
    vec2 px = vec2((ndc.x * 0.5 + 0.5) * float(u_size.x), (0.5 - ndc.y * 0.5) * float(u_size.y));
    if (px.x < 0.0 || px.y < 0.0 || px.x >= float(u_size.x) || px.y >= float(u_size.y)) return false;
    ivec2 top = ivec2(px);
    pix = ivec2(top.x, u_size.y - 1 - top.y);
    return true;
}

float radicalInverse2(uint i) { return float(bitfieldReverse(i)) * 2.3283064365386963e-10; }
vec2 hammersley(uint i, uint n) { return vec2((float(i) + 0.5) / float(n), radicalInverse2(i)); }
float halton3(uint i) {
    float f = 1.0, r = 0.0;
    while (i > 0u) {
        f /= 3.0;
        r += f * float(i % 3u);
        i /= 3u;
    }
    return r;
}

// One estimate of B(x_o) (Eq. 4, W/mm²) at pixel xy with the shifts of its interleave cell.
vec3 gatherExitance(ivec2 xy, vec3 xo, vec3 no) {
    float sgn = no.z >= 0.0 ? 1.0 : -1.0;  // Duff et al. 2017 basis (lucent::Frame)
    float a = -1.0 / (sgn + no.z);
    float bb = no.x * no.y * a;
    vec3 fs = vec3(1.0 + sgn * no.x * no.x * a, sgn * bb, -sgn * no.x);
    vec3 ft = vec3(bb, sgn + no.y * no.y * a, -no.y);

    vec3 sigT = texelFetch(u_sigmaT, xy, 0).rgb, sigS = texelFetch(u_sigmaS, xy, 0).rgb;
    Profile prof[3];
    int channels[3];
    int channelCount = 0;
    float R = texelFetch(u_sigmaS, xy, 0).a;  // disc radius R′, from the irradiance pass
    for (int c = 0; c < 3; ++c) {
        prof[c] = makeProfile(u_model, max(sigT[c] - sigS[c], 0.0), sigS[c], u_boundary);
        if (prof[c].zr > 0.0) channels[channelCount++] = c;
    }
    if (channelCount == 0) return vec3(0.0);
    int nChan[3] = int[3](0, 0, 0);
    for (int i = 0; i < u_nImp; ++i) nChan[channels[i % channelCount]]++;
    float pUniform = (u_nUni > 0 && R > 0.0) ? 1.0 / (PI * R * R) : 0.0;
    int k = u_interleave;
    int cell = ((u_size.y - 1 - xy.y) % k) * k + (xy.x % k);
    vec4 s0 = b_shift[2 * cell], s1 = b_shift[2 * cell + 1];

    vec3 B = vec3(0.0);
    int total = u_nImp + (R > 0.0 ? u_nUni : 0);
    for (int i = 0; i < total; ++i) {
        float rPlane, phi;
        if (i < u_nImp) {
            vec2 h = hammersley(uint(i), uint(u_nImp));
            float uSrc = fract(halton3(uint(i)) + s0.x);
            float uR = fract(h.x + s0.y), uPhi = fract(h.y + s0.z);
            Profile p = prof[channels[i % channelCount]];
            float z = uSrc < p.pReal ? p.zr : p.zv;
            rPlane = sampleSourceRadius(p.sigma, z, uR);
            phi = 2.0 * PI * uPhi;
        } else {
            int j = i - u_nImp;
            vec2 h = hammersley(uint(j), uint(u_nUni));
            rPlane = R * sqrt(fract(h.x + s0.w));
            phi = 2.0 * PI * fract(h.y + s1.x);
        }
        vec3 pPlane = xo + rPlane * (cos(phi) * fs + sin(phi) * ft);
        ivec2 pix;
        if (!projectToPixel(pPlane, pix)) continue;
        vec4 q = texelFetch(u_position, pix, 0);
        if (q.w == 0.0) continue;
        vec3 E = texelFetch(u_irradiance, pix, 0).rgb;
        if (E == vec3(0.0)) continue;  // unlit sample: contributes exactly 0
        // The eye ray through p′ meets the fetched pixel's tangent plane (§6.2).
        vec3 p = q.xyz;
        vec3 np = normalize(texelFetch(u_normal, pix, 0).xyz);
        vec3 origin = u_ortho != 0 ? pPlane : u_eye;
        vec3 dir = u_ortho != 0 ? normalize(u_viewDir) : normalize(pPlane - u_eye);
        float denom = dot(dir, np);
        if (abs(denom) > 0.1) p = origin + dir * (dot(p - origin, np) / denom);
        float r = length(p - xo);
        // Eq. 8–9: |dA_p/dA_p′| = (cos α′/cos α)(d²/d′²), clamped.
        float J = 1.0;
        if (u_jacobian != 0) {
            float cosA = abs(dot(np, towardEye(p)));
            float cosAp = abs(dot(no, towardEye(pPlane)));
            float ratio = 1.0;
            if (u_ortho == 0) {
                float d = length(u_eye - p), dp = length(u_eye - pPlane);
                ratio = dp > 0.0 ? (d * d) / (dp * dp) : 1.0;
            }
            J = cosA > 1e-6 ? min(u_maxJacobian, cosAp / cosA * ratio) : u_maxJacobian;
        }
        // Balance heuristic over channel techniques and the disc: weight/pdf = 1/Σ_t n_t p_t.
        float denomPdf = rPlane <= R ? float(u_nUni) * pUniform : 0.0;
        for (int c = 0; c < 3; ++c)
            if (nChan[c] > 0) denomPdf += float(nChan[c]) * pdfArea(prof[c], rPlane);
        if (!(denomPdf > 0.0)) continue;
        float w = J / denomPdf;
        for (int c = 0; c < 3; ++c) B[c] += rd(prof[c], r) * E[c] * w;
    }
    return B;
}

shared uint s_maxChange;
shared uint s_maxMean;

void main() {
    if (gl_LocalInvocationIndex == 0u) {
        s_maxChange = 0u;
        s_maxMean = 0u;
    }
    barrier();
    ivec2 xy = ivec2(gl_GlobalInvocationID.xy);
    bool inside = xy.x < u_size.x && xy.y < u_size.y;
    vec4 pos = inside ? texelFetch(u_position, xy, 0) : vec4(0.0);
    if (inside && pos.w == 0.0) imageStore(u_target, xy, vec4(0.0));
    if (inside && pos.w != 0.0) {
        vec3 xo = pos.xyz;
        vec3 no = normalize(texelFetch(u_normal, xy, 0).xyz);
        vec3 sum = u_framesBefore > 0 ? imageLoad(u_accum, xy).rgb : vec3(0.0);
        int frames = u_framesBefore;
        if (u_gather != 0) {
            vec3 B = gatherExitance(xy, xo, no);
            vec3 oldMean = frames > 0 ? sum / float(frames) : vec3(0.0);
            sum += B;
            frames += 1;
            vec3 mean = sum / float(frames);
            imageStore(u_accum, xy, vec4(sum, 0.0));
            // Non-negative floats order like their bit patterns: atomicMax on uint, first in
            // shared memory, then once per work group.
            if (frames > 1) {
                vec3 d = abs(mean - oldMean);
                atomicMax(s_maxChange, floatBitsToUint(max(d.r, max(d.g, d.b))));
            }
            atomicMax(s_maxMean, floatBitsToUint(max(mean.r, max(mean.g, mean.b))));
        }
        vec3 mean = frames > 0 ? sum / float(frames) : vec3(0.0);
        // Eq. 3: L = F_t(η, ω_o) B/π, F_t = 1 − F_r for the exit direction.
        float cosO = max(0.0, dot(no, towardEye(xo)));
        float Ft = 1.0 - dipoleFresnelReflectance(cosO, u_eta);
        imageStore(u_target, xy, vec4(mean * (Ft / PI), 0.0));
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u && u_gather != 0) {
        atomicMax(b_maxChange, s_maxChange);
        atomicMax(b_maxMean, s_maxMean);
    }
}
