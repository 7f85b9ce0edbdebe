#version 450 core
// SPDX-License-Identifier: MIT
// Deferred direct lighting: for each covered pixel, the subsurface term supplied by a plug-in
// pass plus Σ_lights f(ωo, ωi) E⊥ cosθi V, with V the shadow-map visibility. Output: linear
// radiance W/(mm²·sr).
#include "common/frame.glsl"
#include "common/lighting.glsl"
#include "common/shadow.glsl"

layout(binding = 0) uniform sampler2D u_position;
layout(binding = 1) uniform sampler2D u_normal;
layout(binding = 2) uniform sampler2D u_subsurface;
layout(binding = 3) uniform sampler2DArrayShadow u_shadowMaps;

layout(std430, binding = LUCENT_BINDING_SURFACES) readonly buffer SurfaceBlock {
    GpuSurface surfaces[];
};

layout(location = 0) out vec4 o_radiance;

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 position = texelFetch(u_position, px, 0);
    bool subsurfaceOnly = frame.flags.w != 0;
    if (position.a == 0.0) {
        o_radiance = subsurfaceOnly ? vec4(0.0, 0.0, 0.0, 1.0) : vec4(frame.background.rgb, 1.0);
        return;
    }
    vec3 radiance = texelFetch(u_subsurface, px, 0).rgb;
    if (!subsurfaceOnly) {
        vec4 normalId = texelFetch(u_normal, px, 0);
        vec3 p = position.xyz;
        vec3 n = normalize(normalId.xyz);
        GpuSurface s = surfaces[max(int(normalId.a + 0.5) - 1, 0)];
        vec3 v = frame.cameraPosition.w > 0.5 ? -frame.cameraForward.xyz
                                              : normalize(frame.cameraPosition.xyz - p);
        for (int i = 0; i < frame.flags.x; ++i) {
            vec3 wi;
            vec3 irradiance;
            float dist;
            lightIncidence(lights[i], p, wi, irradiance, dist);
            vec3 fcos = surfaceBrdfCos(s, n, v, wi, frame.flags.z != 0);
            if (all(equal(fcos, vec3(0.0)))) continue;
            float visibility =
                frame.flags.y != 0 ? shadowVisibility(u_shadowMaps, lights[i], p, n) : 1.0;
            radiance += fcos * irradiance * visibility;
        }
    }
    o_radiance = vec4(radiance, 1.0);
}
