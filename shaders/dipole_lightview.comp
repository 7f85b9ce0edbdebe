#version 450 core
// SPDX-License-Identifier: MIT
// Skip criterion of a light view (dipole::DipoleSubsurfaceProvider; GLSL mirror of
// dipole::backlitFluxFraction in engine/src/dipole/ImageSpace.cpp): per light-view texel with
// E > 0 the flux through it, lum(E)·dA with dA = footprint²/max(cos α, 0.05); "back-lit" when
// the camera does not see the point (visibleIn rule of dipole_lightview.glsl) but the camera
// texel in front of it along the camera ray lies within that pixel's disc radius
// min(R′, maxRadius). Output: one (Σ flux, Σ back-lit flux) pair per work group; the host sums.
// The light view is layer u_layer of the provider's light-view arrays (one layer per light,
// kept across camera and material changes).
#include "dipole_lightview.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2DArray u_lvPosition;    // light views: xyz mm, a covered
layout(binding = 1) uniform sampler2DArray u_lvNormal;      // outward unit normal
layout(binding = 2) uniform sampler2DArray u_lvIrradiance;  // E (W/mm²)
layout(binding = 3) uniform sampler2D u_camPosition;   // camera G-buffer
layout(binding = 4) uniform sampler2D u_camNormal;
layout(binding = 5) uniform sampler2D u_camSigmaS;     // a: disc radius min(R′, maxRadius), mm

layout(std430, binding = 0) writeonly buffer PartialBlock { vec2 b_partial[]; };

uniform mat4 u_clip[2];  // 0 camera, 1 light view
uniform vec4 u_eyeOrtho[2];
uniform vec3 u_dir[2];
uniform ivec2 u_size[2];
uniform int u_layer;  // the light view's layer

mat4 viewClip(int v) { return u_clip[v]; }
bool viewOrtho(int v) { return u_eyeOrtho[v].w > 0.5; }
vec3 viewEye(int v) { return u_eyeOrtho[v].xyz; }
vec3 viewDirection(int v) { return u_dir[v]; }
ivec2 viewSize(int v) { return u_size[v]; }
vec4 viewPosition(int v, ivec2 pix) {
    return v == 0 ? texelFetch(u_camPosition, pix, 0)
                  : texelFetch(u_lvPosition, ivec3(pix, u_layer), 0);
}
vec3 viewNormal(int v, ivec2 pix) {
    return v == 0 ? texelFetch(u_camNormal, pix, 0).xyz
                  : texelFetch(u_lvNormal, ivec3(pix, u_layer), 0).xyz;
}
vec3 viewIrradiance(int v, ivec2 pix) {
    return texelFetch(u_lvIrradiance, ivec3(pix, u_layer), 0).rgb;
}

shared vec2 s_sum[64];

void main() {
    ivec2 xy = ivec2(gl_GlobalInvocationID.xy);
    vec2 mine = vec2(0.0);
    if (xy.x < u_size[1].x && xy.y < u_size[1].y) {
        vec4 q = viewPosition(1, xy);
        vec3 E = viewIrradiance(1, xy);
        if (q.w != 0.0 && E != vec3(0.0)) {
            vec3 p = q.xyz;
            vec3 n = normalize(viewNormal(1, xy));
            float fp = pixelFootprint(1, p);
            float cosA = max(0.05, abs(dot(n, towardEyeOf(1, p))));
            float flux = dot(E, vec3(0.2126, 0.7152, 0.0722)) * fp * fp / cosA;
            mine.x = flux;
            ViewHit front;
            if (lookUp(0, p, front)) {
                float dist = length(front.p - p);
                bool seen = dist <= pixelFootprint(0, p) + fp;
                if (!seen && dist <= texelFetch(u_camSigmaS, front.pix, 0).a) mine.y = flux;
            }
        }
    }
    uint i = gl_LocalInvocationIndex;
    s_sum[i] = mine;
    barrier();
    for (uint stride = 32u; stride > 0u; stride >>= 1) {
        if (i < stride) s_sum[i] += s_sum[i + stride];
        barrier();
    }
    if (i == 0u) b_partial[gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x] = s_sum[0];
}
