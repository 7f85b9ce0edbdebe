#version 450 core
// SPDX-License-Identifier: MIT
// Deferred direct lighting: for each covered pixel, Σ_lights f(ωo, ωi) E⊥ cosθi V (V the
// shadow-map visibility) plus the subsurface term supplied by a plug-in pass. Outputs: linear
// radiance W/(mm²·sr) (location 0) and the direct term alone, a = coverage (location 1), which
// the renderer keeps and reuses while the G-buffer, lights, shadow maps and surfaces are
// unchanged, e.g. during a paint stroke: compiled with REUSE_DIRECT, the program only adds the
// stored term to the subsurface one (a separate program, not a uniform branch: llvmpipe runs
// both sides of a branch under an execution mask). Both variants sum direct + subsurface in
// the same order, so a reused frame is bit-identical to a recomputed one.
#include "common/frame.glsl"
#include "common/lighting.glsl"
#include "common/shadow.glsl"

layout(binding = 0) uniform sampler2D u_position;
layout(binding = 1) uniform sampler2D u_normal;
layout(binding = 2) uniform sampler2D u_subsurface;
layout(binding = 3) uniform sampler2DArrayShadow u_shadowMaps;
layout(binding = 4) uniform sampler2D u_directCache;

layout(std430, binding = LUCENT_BINDING_SURFACES) readonly buffer SurfaceBlock {
    GpuSurface surfaces[];
};

layout(location = 0) out vec4 o_radiance;
layout(location = 1) out vec4 o_direct;

// Direct term of pixel px: rgb radiance, a = 1 where a mesh covers the pixel, else 0 (rgb then
// the background, or black for subsurface-only frames).
vec4 directTerm(ivec2 px) {
    vec4 position = texelFetch(u_position, px, 0);
    bool subsurfaceOnly = frame.flags.w != 0;
    if (position.a == 0.0)
        return subsurfaceOnly ? vec4(0.0) : vec4(frame.background.rgb, 0.0);
    vec3 radiance = vec3(0.0);
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
    return vec4(radiance, 1.0);
}

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
#ifdef REUSE_DIRECT
    vec4 direct = texelFetch(u_directCache, px, 0);
#else
    vec4 direct = directTerm(px);
    o_direct = direct;
#endif
    vec3 subsurface = direct.a > 0.5 ? texelFetch(u_subsurface, px, 0).rgb : vec3(0.0);
    o_radiance = vec4(direct.rgb + subsurface, 1.0);
}
