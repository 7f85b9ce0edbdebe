#version 450 core
// SPDX-License-Identifier: MIT
// Texel lists of dipole::DirpoleSubsurfaceProvider (docs/methods/dipole.md §7, "Latency"):
//  - without FROM_LIST, over the whole 6-layer face grid: the covered texels (after the face
//    G-buffers are rendered; u_target = 0xffffffff);
//  - with FROM_LIST, over that covered list: the gather's work list, the texels with fewer than
//    u_target samples.
// Entries are packTexel() words in any order (a texel's sum does not depend on the order). The
// passes after it run one invocation per listed texel: llvmpipe executes a branch for a whole
// SIMD row under its execution mask, so a pass over every texel pays the per-texel set-up
// (material lookup, profiles, hashes) of all 6 × cubeMapSize² of them even when only the
// texels under a stroke sample.
#include "dirpole_common.glsl"
#include "common/dispatch.glsl"

#ifdef FROM_LIST
layout(local_size_x = 64) in;
layout(std430, binding = 6) readonly buffer Source { uint b_source[]; };
uniform uint u_sourceCount;
#else
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
uniform int u_faceSize;
#endif

layout(binding = 0) uniform sampler2DArray u_facePosition;  // xyz mm, a covered
layout(binding = 1) uniform sampler2DArray u_accum;         // a = the texel's sample count N

layout(std430, binding = 5) writeonly buffer Output { uint b_texels[]; };

uniform uint u_target;

shared uint s_count;
shared uint s_base;

void main() {
    if (gl_LocalInvocationIndex == 0u) s_count = 0u;
    barrier();
#ifdef FROM_LIST
    uint entry = lineGroup() * 64u + gl_LocalInvocationIndex;  // gpu::dispatchLine
    bool valid = entry < u_sourceCount;
    ivec3 id = unpackTexel(valid ? b_source[entry] : 0u);
#else
    ivec3 id = ivec3(gl_GlobalInvocationID);
    bool valid = id.x < u_faceSize && id.y < u_faceSize &&
                 texelFetch(u_facePosition, id, 0).w != 0.0;
#endif
    bool listed = false;
    uint slot = 0u;
    if (valid && uint(texelFetch(u_accum, id, 0).a) < u_target) {
        listed = true;
        slot = atomicAdd(s_count, 1u);
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u && s_count > 0u) s_base = atomicAdd(b_listed, s_count);
    barrier();
    if (listed) b_texels[s_base + slot] = packTexel(id);
}
