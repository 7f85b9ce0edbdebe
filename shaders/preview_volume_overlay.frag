#version 450 core
// SPDX-License-Identifier: MIT
// App overlay (owner: app; app/gui/PreviewRenderer.cpp): the painted volume drawn over the
// tone-mapped preview with post_fullscreen.vert and alpha blending, so artists see what lies
// below the surface. Only pixels the G-buffer covers are marched (inside voxels lie inside the
// mesh), from one voxel before the front surface to the far side of the object's box (the
// volume grid ∩ the mesh bounds), at most u_maxSteps samples, never finer than half a voxel; the
// largest channel value met inside the object (maximum-intensity projection) is colour-mapped
// with the slice view's viridis (SliceView.cpp: nine matplotlib samples, linear in between,
// display values) over the volume's value range, at opacity u_opacity. Pixels whose ray meets
// no inside voxel are left untouched. Units: mm.

layout(binding = 0) uniform sampler3D u_values;  // R32F, texel = voxel; outside voxels < -1e29
layout(binding = 1) uniform sampler2D u_position;  // G-buffer: rgb world position, a coverage

uniform mat4 u_worldFromClip;  // inverse of the render camera's clipFromWorld
uniform vec2 u_viewport;       // framebuffer size, pixels
uniform vec3 u_boxMin;         // mm
uniform vec3 u_boxMax;         // mm
uniform vec3 u_gridOrigin;     // mm, minimum corner of voxel (0,0,0)
uniform float u_voxelSize;     // mm
uniform int u_resolution;      // voxels per axis
uniform vec2 u_range;          // channel value mapped to viridis 0 and 1
uniform float u_opacity;       // [0, 1]
uniform int u_maxSteps;

layout(location = 0) out vec4 o_color;

const vec3 VIRIDIS[9] = vec3[9](vec3(0.267, 0.005, 0.329), vec3(0.283, 0.141, 0.458),
                                vec3(0.254, 0.265, 0.530), vec3(0.207, 0.372, 0.553),
                                vec3(0.164, 0.471, 0.558), vec3(0.128, 0.567, 0.551),
                                vec3(0.135, 0.659, 0.518), vec3(0.478, 0.821, 0.318),
                                vec3(0.993, 0.906, 0.144));

vec3 viridis(float t) {
    t = clamp(t, 0.0, 1.0) * 8.0;
    int i = min(int(t), 7);
    return mix(VIRIDIS[i], VIRIDIS[i + 1], t - float(i));
}

void main() {
    vec2 uv = gl_FragCoord.xy / u_viewport;
    ivec2 gsize = textureSize(u_position, 0);  // the G-buffer may be smaller (reduced resolution)
    vec4 surface = texelFetch(u_position, clamp(ivec2(uv * vec2(gsize)), ivec2(0), gsize - 1), 0);
    if (surface.a < 0.5) discard;
    vec2 ndc = uv * 2.0 - 1.0;
    vec4 a = u_worldFromClip * vec4(ndc, -1.0, 1.0);
    vec4 b = u_worldFromClip * vec4(ndc, 1.0, 1.0);
    vec3 o = a.xyz / a.w;
    vec3 d = normalize(b.xyz / b.w - o);
    // Ray/box slabs (Kay & Kajiya 1986); IEEE infinities handle axis-parallel rays.
    vec3 inv = 1.0 / d;
    vec3 t0 = (u_boxMin - o) * inv, t1 = (u_boxMax - o) * inv;
    vec3 tLo = min(t0, t1), tHi = max(t0, t1);
    float tNear = max(max(tLo.x, tLo.y), max(tLo.z, dot(surface.xyz - o, d) - u_voxelSize));
    float tFar = min(min(tHi.x, tHi.y), tHi.z);
    if (!(tNear < tFar)) discard;
    float dt = max(0.5 * u_voxelSize, (tFar - tNear) / float(max(u_maxSteps, 1)));
    float best = -3.0e38;
    for (float t = tNear + 0.5 * dt; t < tFar; t += dt) {
        ivec3 c = ivec3(floor((o + t * d - u_gridOrigin) / u_voxelSize));
        if (any(lessThan(c, ivec3(0))) || any(greaterThanEqual(c, ivec3(u_resolution)))) continue;
        best = max(best, texelFetch(u_values, c, 0).r);
    }
    if (best < -1.0e29) discard;  // no inside voxel along the ray
    // As the slice view: a degenerate range maps everything to viridis(0).
    float span = u_range.y > u_range.x ? u_range.y - u_range.x : 1.0;
    o_color = vec4(viridis((best - u_range.x) / span), u_opacity);
}
