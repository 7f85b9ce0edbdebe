#version 450 core
// SPDX-License-Identifier: MIT
// Image-space dipole gather (Mertens et al. 2005 §4–6), GLSL port of
// engine/src/dipole/ImageSpace.cpp (same samples, same weights; float arithmetic).
// One invocation per pixel: tangent-plane importance samples of R_d(r)·r per channel (exact
// sampling, §4) + uniform disc samples, combined by the multi-sample balance heuristic (§6.1),
// projected into the camera buffers, Eq. 9 Jacobian, interleaved Cranley–Patterson shifts.
// Output: exitance B(x_o) of Eq. 4 (W/mm²) per pixel.
#include "dipole_profiles.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, binding = 0) readonly buffer PositionBlock { vec4 b_position[]; };  // w: covered
layout(std430, binding = 1) readonly buffer NormalBlock { vec4 b_normal[]; };
layout(std430, binding = 2) readonly buffer IrradianceBlock { vec4 b_irradiance[]; };
layout(std430, binding = 3) readonly buffer MaterialBlock { vec4 b_material[]; };  // σt, σs′ pairs
layout(std430, binding = 4) readonly buffer ShiftBlock { vec4 b_shift[]; };        // 2 per cell
layout(std430, binding = 5) writeonly buffer ExitanceBlock { vec4 b_exitance[]; };

uniform mat4 u_clipFromWorld;
uniform vec3 u_eye;
uniform vec3 u_viewDir;
uniform int u_ortho;
uniform ivec2 u_size;
uniform int u_model;        // 0 dipole, 1 better dipole
uniform vec3 u_boundary;    // F_dr, C1, C2
uniform int u_nImp;
uniform int u_nUni;
uniform float u_discQuantile;
uniform float u_maxRadius;  // mm; > 0: only r ≤ u_maxRadius (GatherSettings::maxRadius)
uniform int u_jacobian;
uniform float u_maxJacobian;
uniform int u_interleave;

const float PI = 3.14159265358979;

vec3 towardEye(vec3 p) { return u_ortho != 0 ? -normalize(u_viewDir) : normalize(u_eye - p); }

bool projectToPixel(vec3 p, out ivec2 pix) {
    vec4 clip = u_clipFromWorld * vec4(p, 1.0);
    if (!(clip.w > 0.0)) return false;
    vec2 ndc = clip.xy / clip.w;
    vec2 px = vec2((ndc.x * 0.5 + 0.5) * float(u_size.x), (0.5 - ndc.y * 0.5) * float(u_size.y));
    if (px.x < 0.0 || px.y < 0.0 || px.x >= float(u_size.x) || px.y >= float(u_size.y)) return false;
    pix = ivec2(px);
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

void main() {
    ivec2 xy = ivec2(gl_GlobalInvocationID.xy);
    if (xy.x >= u_size.x || xy.y >= u_size.y) return;
    int idx = xy.y * u_size.x + xy.x;
    vec4 pos = b_position[idx];
    if (pos.w == 0.0) {
        b_exitance[idx] = vec4(0.0);
        return;
    }
    vec3 xo = pos.xyz;
    vec3 no = normalize(b_normal[idx].xyz);
    // Duff et al. 2017 orthonormal basis (same as lucent::Frame).
    float sgn = no.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sgn + no.z);
    float bb = no.x * no.y * a;
    vec3 fs = vec3(1.0 + sgn * no.x * no.x * a, sgn * bb, -sgn * no.x);
    vec3 ft = vec3(bb, sgn + no.y * no.y * a, -no.y);

    vec3 sigT = b_material[2 * idx].xyz, sigS = b_material[2 * idx + 1].xyz;
    Profile prof[3];
    vec3 masses[3];
    int channels[3];
    int channelCount = 0;
    float R = 0.0;
    for (int c = 0; c < 3; ++c) {
        prof[c] = makeProfile(u_model, max(sigT[c] - sigS[c], 0.0), sigS[c], u_boundary);
        masses[c] = windowMasses(prof[c], u_maxRadius);
        if (prof[c].zr > 0.0) {
            channels[channelCount++] = c;
            R = max(R, sampleSourceRadius(prof[c].sigma, prof[c].zv, u_discQuantile));
        }
    }
    if (u_maxRadius > 0.0) R = min(R, u_maxRadius);
    if (channelCount == 0) {
        b_exitance[idx] = vec4(0.0);
        return;
    }
    int nChan[3] = int[3](0, 0, 0);
    for (int i = 0; i < u_nImp; ++i) nChan[channels[i % channelCount]]++;
    float pUniform = (u_nUni > 0 && R > 0.0) ? 1.0 / (PI * R * R) : 0.0;
    int cell = (xy.y % u_interleave) * u_interleave + (xy.x % u_interleave);
    vec4 s0 = b_shift[2 * cell], s1 = b_shift[2 * cell + 1];

    vec3 B = vec3(0.0);
    int total = u_nImp + (R > 0.0 ? u_nUni : 0);
    for (int i = 0; i < total; ++i) {
        float rPlane, phi;
        if (i < u_nImp) {
            vec2 h = hammersley(uint(i), uint(u_nImp));
            float uSrc = fract(halton3(uint(i)) + s0.x);
            float uR = fract(h.x + s0.y), uPhi = fract(h.y + s0.z);
            int c = channels[i % channelCount];
            rPlane = sampleWindowed(prof[c], masses[c], u_maxRadius, uSrc, uR);
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
        int j = pix.y * u_size.x + pix.x;
        vec4 q = b_position[j];
        if (q.w == 0.0) continue;
        vec3 p = q.xyz;
        vec3 np = normalize(b_normal[j].xyz);
        vec3 origin = u_ortho != 0 ? pPlane : u_eye;
        vec3 dir = u_ortho != 0 ? normalize(u_viewDir) : normalize(pPlane - u_eye);
        float denom = dot(dir, np);
        if (abs(denom) > 0.1) p = origin + dir * (dot(p - origin, np) / denom);
        // x_o's own pixel: its tangent plane holds pPlane, so the ray meets it at pPlane (r = r')
        // at any angle; the grazing fallback above gave r = 0 (issue-6 edge outlier; as
        // ImageSpace.cpp, docs/methods/dipole.md §3).
        if (j == idx) {
            p = pPlane;
            np = no;
        }
        float r = length(p - xo);
        if (u_maxRadius > 0.0 && r > u_maxRadius) continue;  // outside the local-radius window
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
        float denomPdf = rPlane <= R ? float(u_nUni) * pUniform : 0.0;
        for (int c = 0; c < 3; ++c)
            if (nChan[c] > 0)
                denomPdf += float(nChan[c]) * pdfWindowed(prof[c], masses[c], u_maxRadius, rPlane);
        if (!(denomPdf > 0.0)) continue;
        vec3 E = b_irradiance[j].xyz;
        float w = J / denomPdf;
        for (int c = 0; c < 3; ++c) B[c] += rd(prof[c], r) * E[c] * w;
    }
    b_exitance[idx] = vec4(B, 0.0);
}
