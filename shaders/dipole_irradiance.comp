#version 450 core
// SPDX-License-Identifier: MIT
// Irradiance pass of the GPU image-space dipole (dipole::DipoleSubsurfaceProvider; Mertens et al. 2005 §5):
// per covered G-buffer pixel, the Fresnel-transmitted irradiance of Eq. 5,
//   E = Σ_lights F_t(η, cos θ_i) · E⊥ · cos θ_i · V,   F_t = 1 − F_r,
// with E⊥ and V exactly as the renderer's shading pass (common/lighting.glsl, common/shadow.glsl),
// and the painted material just inside the surface (dipole_material.glsl, the lookup of
// dipole::buildSurfaceBuffers).
// Also the radius R′ of the uniform disc samples (the discQuantile quantile of the widest
// channel's virtual source, as the CPU gather's PixelMaterial), so the per-frame gather does not
// repeat the three Newton solves. Outputs (GL rows, bottom first): E (W/mm²), σt and σs′ (mm⁻¹),
// R′ (mm) in the σs′ image's alpha.
// LIGHT_VIEW 1 (the light views of Mertens et al. 2005 §7.1, docs/methods/dipole.md §3d): E only. The
// gather takes the profile from x_o's material, so a light view needs neither the material
// nor R′ (three Newton solves per texel); a separate program, not a uniform branch (llvmpipe
// runs both sides of a branch under its execution mask).
#ifndef LIGHT_VIEW
#define LIGHT_VIEW 0
#endif
#include "common/lighting.glsl"
#include "common/shadow.glsl"
#include "dipole_fresnel.glsl"
#include "dipole_material.glsl"
#include "dipole_profiles.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2D u_position;  // G-buffer: xyz mm, a coverage
layout(binding = 1) uniform sampler2D u_normal;    // G-buffer: unit normal facing the camera
layout(binding = 2) uniform sampler2DArrayShadow u_shadowMaps;
layout(binding = 3) uniform sampler3D u_volumeSigmaT;  // rgb σt (mm⁻¹), a inside
layout(binding = 4) uniform sampler3D u_volumeSigmaS;  // rgb σs′ (mm⁻¹)

layout(rgba32f, binding = 0) writeonly uniform image2D o_irradiance;
#if !LIGHT_VIEW
layout(rgba32f, binding = 1) writeonly uniform image2D o_sigmaT;
layout(rgba32f, binding = 2) writeonly uniform image2D o_sigmaS;
// min and max of R′ over the object's pixels (floats ≥ 0 order like their bit patterns).
layout(std430, binding = 3) buffer RadiusBlock { uint b_minRadius; uint b_maxRadius; };
#endif

uniform ivec2 u_size;
uniform int u_lightCount;
uniform int u_shadows;
uniform float u_eta;
uniform int u_hasMaterial;
uniform vec3 u_gridOrigin;   // mm
uniform float u_voxelSize;   // mm
uniform int u_resolution;
uniform int u_model;  // 0 dipole, 1 better dipole
uniform vec3 u_boundary;  // F_dr, C1, C2
uniform float u_discQuantile;
uniform float u_maxRadius;  // mm; > 0: R′ is capped at the local-radius window
uniform int u_meshId;  // −1: every mesh; else only pixels of this mesh (G-buffer normal.a − 1)

void main() {
    ivec2 xy = ivec2(gl_GlobalInvocationID.xy);
    if (xy.x >= u_size.x || xy.y >= u_size.y) return;
    vec4 pos = texelFetch(u_position, xy, 0);
    vec4 normalId = texelFetch(u_normal, xy, 0);
    bool ours = u_meshId < 0 || int(normalId.a + 0.5) - 1 == u_meshId;
    vec3 E = vec3(0.0), sigT = vec3(0.0), sigS = vec3(0.0);
    if (pos.w != 0.0 && ours) {
        vec3 p = pos.xyz;
        vec3 n = normalize(normalId.xyz);
        for (int i = 0; i < u_lightCount; ++i) {
            vec3 wi, incident;
            float dist;
            lightIncidence(lights[i], p, wi, incident, dist);
            float cosI = dot(n, wi);
            if (cosI <= 0.0) continue;
            float V = u_shadows != 0 ? shadowVisibility(u_shadowMaps, lights[i], p, n) : 1.0;
            E += incident * ((1.0 - dipoleFresnelReflectance(cosI, u_eta)) * cosI * V);
        }
#if !LIGHT_VIEW
        if (u_hasMaterial != 0)
            dipoleMaterialInside(u_volumeSigmaT, u_volumeSigmaS, u_gridOrigin, u_voxelSize,
                                 u_resolution, p, n, sigT, sigS);
#endif
    }
#if LIGHT_VIEW
    imageStore(o_irradiance, xy, vec4(E, pos.w));
#else
    float R = discRadius(u_model, sigT, sigS, u_boundary, u_discQuantile, u_maxRadius);
    if (R > 0.0) {
        atomicMin(b_minRadius, floatBitsToUint(R));
        atomicMax(b_maxRadius, floatBitsToUint(R));
    }
    imageStore(o_irradiance, xy, vec4(E, pos.w));
    imageStore(o_sigmaT, xy, vec4(sigT, 0.0));
    imageStore(o_sigmaS, xy, vec4(sigS, R));
#endif
}
