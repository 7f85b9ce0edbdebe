#version 450 core
// SPDX-License-Identifier: MIT
// G-buffer pass, fragment stage: world position (a = coverage) and the interpolated vertex
// normal, renormalised and put on the viewer's side of the facet (a = mesh id + 1). The side
// comes from the facet's geometric normal (screen-space derivatives of the position), so it
// does not depend on the triangles' winding.
#include "common/frame.glsl"

layout(location = 0) uniform int u_meshId;

in vec3 v_position;
in vec3 v_normal;

layout(location = 0) out vec4 o_position;
layout(location = 1) out vec4 o_normal;

void main() {
    vec3 n = normalize(v_normal);
    vec3 ng = cross(dFdx(v_position), dFdy(v_position));
    vec3 toEye = frame.cameraPosition.w > 0.5 ? -frame.cameraForward.xyz
                                              : frame.cameraPosition.xyz - v_position;
    if (dot(ng, toEye) < 0.0) ng = -ng;  // geometric normal facing the viewer
    if (dot(n, ng) < 0.0) n = -n;
    o_position = vec4(v_position, 1.0);
    o_normal = vec4(n, float(u_meshId + 1));
}
