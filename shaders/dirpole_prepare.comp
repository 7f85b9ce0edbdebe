#version 450 core
// SPDX-License-Identifier: MIT
// Prepare pass of dipole::DirpoleSubsurfaceProvider, before each gather (docs/methods/dipole.md
// §7, "Latency"): a face texel's running sum C^f(x_o) depends on the material only through σt,
// σs′ just inside x_o (the gather builds S_d and the samplers from x_o's material, the dirpole thesis §4.1
// step 2), so a texel whose material differs from the one its sum was computed for restarts
// (sum and count 0) and stores the new material; every other texel keeps its sum. The gather
// then reads the stored material instead of looking it up again.
// Counts for the CPU's frame plan: covered texels, restarted texels, the fewest and the most
// samples of any covered texel.
#include "dirpole_common.glsl"
#include "common/dispatch.glsl"

layout(local_size_x = 64) in;  // one invocation per covered texel

// The covered texels (dirpole_compact.comp after the face G-buffers were rendered).
layout(std430, binding = 6) readonly buffer Source { uint b_source[]; };
uniform uint u_sourceCount;

layout(binding = 0) uniform sampler2DArray u_facePosition;  // xyz mm, a covered
layout(binding = 1) uniform sampler2DArray u_faceNormal;    // outward unit normal

layout(rgba32f, binding = 0) uniform image2DArray u_accum;  // rgb Σ samples, a = count N
layout(rgba32f, binding = 1) uniform image2DArray u_matT;   // σt rgb (mm⁻¹), a = 1 once set
layout(rgba32f, binding = 2) uniform image2DArray u_matS;   // σs′ rgb (mm⁻¹)


shared uint s_covered, s_restarted, s_minN, s_maxN;

void main() {
    if (gl_LocalInvocationIndex == 0u) {
        s_covered = 0u;
        s_restarted = 0u;
        s_minN = 0xffffffffu;
        s_maxN = 0u;
    }
    barrier();
    uint entry = lineGroup() * 64u + gl_LocalInvocationIndex;  // gpu::dispatchLine
    bool valid = entry < u_sourceCount;
    ivec3 id = unpackTexel(valid ? b_source[entry] : 0u);
    vec4 pos = valid ? texelFetch(u_facePosition, id, 0) : vec4(0.0);
    if (pos.w != 0.0) {
        vec3 sigT, sigS;
        materialInside(pos.xyz, texelFetch(u_faceNormal, id, 0).xyz, sigT, sigS);
        vec4 oldT = imageLoad(u_matT, id);
        vec4 oldS = imageLoad(u_matS, id);
        vec4 acc = imageLoad(u_accum, id);
        if (oldT.a == 0.0 || oldT.rgb != sigT || oldS.rgb != sigS) {
            imageStore(u_matT, id, vec4(sigT, 1.0));
            imageStore(u_matS, id, vec4(sigS, 0.0));
            acc = vec4(0.0);
            imageStore(u_accum, id, acc);
            atomicAdd(s_restarted, 1u);
        }
        uint n = uint(acc.a);
        atomicAdd(s_covered, 1u);
        atomicMin(s_minN, n);
        atomicMax(s_maxN, n);
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u && s_covered > 0u) {
        atomicAdd(b_covered, s_covered);
        atomicAdd(b_restarted, s_restarted);
        atomicMin(b_minN, s_minN);
        atomicMax(b_maxN, s_maxN);
    }
}
