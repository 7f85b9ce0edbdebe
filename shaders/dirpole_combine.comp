#version 450 core
// SPDX-License-Identifier: MIT
// Combination pass of dipole::DirpoleSubsurfaceProvider (the dirpole thesis §4.1 step 3): every camera
// pixel x_o of the object averages the cube faces that see it,
//   L(x_o) = T₂₁(ω_o) · Σ_f V_f C̄^f(x_proj^f) / Σ_f V_f,
// C̄^f the running mean (rgb / sample count a of the gather pass's accumulator; a face texel
// without samples does not count) interpolated bilinearly between the texels of x_o's surface,
// T₂₁ = 1 − F_r(η, n_o·ω_o) (Fresnel), and with the exact energy target the exit-angle
// correction c(α′, t) of x_o's material per channel (lucent::dipole::DirpoleExitTable: the
// half-space's angular distribution of the light leaving, t = n_o·ω_o).
// Seed 001 §4.3.2 (cube-map intrusion): faces are looked up at x′_o = x_o − ε_c n_o.
// Seed 001 §4.3.3 (shadow bias): the face's stored window depth z_tex becomes a world distance
// along the face axis, z = z_near + (z_far − z_near) z_tex (the §4.3.3 formula for an
// orthographic camera, measured from the camera instead of as a world z coordinate), and
// V_f = 1 iff the distance of x′_o along the axis is < z + ε_b (+ a slope-scaled term,
// DirpoleSettings::slopeBias, for surfaces seen at grazing angles), and the face sees the front
// of the surface at less than 84° (n_o·(−axis) ≥ 0.1; an edge-on face holds other surfaces).
#include "dipole_fresnel.glsl"
#include "dirpole_common.glsl"
#include "shared/DirpoleShared.h"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2D u_position;       // camera G-buffer: xyz mm, a covered
layout(binding = 1) uniform sampler2D u_normal;         // unit normal facing the camera; a id+1
layout(binding = 2) uniform sampler2DArray u_faceDepth;  // window depth per face
layout(binding = 3) uniform sampler2DArray u_accum;      // rgb Σ C^f over a samples

layout(rgba32f, binding = 0) writeonly uniform image2D u_target;

#define LUCENT_EXIT_TABLE_BINDING LUCENT_DIRPOLE_BINDING_EXIT_TABLE
#include "common/exit_table.glsl"
uniform int u_exitCorrection;

uniform ivec2 u_size;
uniform int u_faceSize;
uniform vec3 u_faceEye[6];   // camera position of each face (mm)
uniform vec3 u_faceAxis[6];  // unit view direction of each face
uniform vec2 u_faceNearFar;  // z_near, z_far (mm), the same for every face
uniform float u_intrusion;   // ε_c (mm), 0 when the fix is off
uniform float u_bias;        // ε_b (mm)
uniform float u_slopeBias;   // extra bias per face texel and unit tan θ (0: constant ε_b)
uniform float u_faceTexel;   // face texel size (mm)
uniform float u_eta;
uniform vec3 u_eye;
uniform vec3 u_viewDir;
uniform int u_ortho;
uniform int u_meshId;  // −1: every mesh; else only pixels of this mesh

void main() {
    ivec2 xy = ivec2(gl_GlobalInvocationID.xy);
    if (xy.x >= u_size.x || xy.y >= u_size.y) return;
    vec4 pos = texelFetch(u_position, xy, 0);
    vec4 normalId = texelFetch(u_normal, xy, 0);
    bool ours = u_meshId < 0 || int(normalId.a + 0.5) - 1 == u_meshId;
    if (pos.w == 0.0 || !ours) {
        imageStore(u_target, xy, vec4(0.0));
        return;
    }
    vec3 xo = pos.xyz;
    vec3 no = normalize(normalId.xyz);
    vec3 xc = xo - u_intrusion * no;  // the dirpole thesis §4.3.2
    vec3 sum = vec3(0.0);
    int visible = 0;
    for (int f = 0; f < 6; ++f) {
        vec2 uv = (u_faceClipFromWorld[f] * vec4(xc, 1.0)).xy * 0.5 + 0.5;  // orthographic: w = 1
        if (any(lessThan(uv, vec2(0.0))) || any(greaterThanEqual(uv, vec2(1.0)))) continue;
        // Slope-scaled extension of ε_b: across one texel a surface at angle θ to the face
        // axis spans h·tan θ of depth, which a constant ε_b cannot absorb at grazing angles.
        float cosF = -dot(no, u_faceAxis[f]);
        if (cosF < 0.1) continue;  // seen from behind or edge-on (> 84°): not by this face
        float tanF = sqrt(max(0.0, 1.0 - cosF * cosF)) / cosF;
        float bias = u_bias + u_slopeBias * u_faceTexel * tanF;
        float zPoint = dot(xc - u_faceEye[f], u_faceAxis[f]);
        // C̄^f at x_proj^f: bilinear over the four nearest texels that hold this surface (the
        // nearest texel alone made every face texel a flat block on screen, visible as blocky
        // stroke edges once a texel covers several pixels). A texel counts when it has samples
        // and its surface is x_o's: the §4.3.3 visibility test (not hidden, zPoint < z + ε_b)
        // and, for the neighbours, not a surface further along the axis either (z < zPoint +
        // ε_b). The weights of the texels that count are renormalised.
        vec2 st = uv * float(u_faceSize) - 0.5;
        ivec2 i0 = ivec2(floor(st));
        vec2 fr = st - vec2(i0);
        vec3 faceSum = vec3(0.0);
        float faceWeight = 0.0;
        for (int k = 0; k < 4; ++k) {
            ivec2 o = ivec2(k & 1, k >> 1);
            float w = (o.x == 1 ? fr.x : 1.0 - fr.x) * (o.y == 1 ? fr.y : 1.0 - fr.y);
            ivec2 t = i0 + o;
            if (w <= 0.0 || any(lessThan(t, ivec2(0))) || any(greaterThanEqual(t, ivec2(u_faceSize))))
                continue;
            ivec3 texel = ivec3(t, f);
            float zTex = texelFetch(u_faceDepth, texel, 0).r;
            if (zTex >= 1.0) continue;  // nothing rasterised there
            float zStored = u_faceNearFar.x + (u_faceNearFar.y - u_faceNearFar.x) * zTex;
            if (!(zPoint < zStored + bias) || !(zStored < zPoint + bias)) continue;
            vec4 acc = texelFetch(u_accum, texel, 0);
            if (acc.a == 0.0) continue;  // no samples yet
            faceSum += w * (acc.rgb / acc.a);
            faceWeight += w;
        }
        if (!(faceWeight > 0.0)) continue;  // V_f = 0: hidden from face f (or no samples)
        sum += faceSum / faceWeight;
        ++visible;
    }
    vec3 C = visible > 0 ? sum / float(visible) : vec3(0.0);
    vec3 toEye = u_ortho != 0 ? -normalize(u_viewDir) : normalize(u_eye - xo);
    float cosO = max(0.0, dot(no, toEye));
    float T21 = 1.0 - dipoleFresnelReflectance(cosO, u_eta);
    if (u_exitCorrection != 0) {
        vec3 sigT, sigS;
        if (materialInside(xo, no, sigT, sigS))
            for (int c = 0; c < 3; ++c)
                if (sigS[c] > 0.0) C[c] *= exitCorrection(sigS[c] / max(sigT[c], sigS[c]), cosO);
    }
    imageStore(u_target, xy, vec4(C * T21, 0.0));
}
