#version 450 core
// SPDX-License-Identifier: MIT
// Light-view and cube-face G-buffers of dipole::DirpoleSubsurfaceProvider, fragment stage:
// world position (a = 1 covered) and the outward unit normal (the interpolated vertex normal;
// the object's meshes carry outward normals). The nearest surface wins (depth test).

in vec3 v_position;
in vec3 v_normal;

layout(location = 0) out vec4 o_position;
layout(location = 1) out vec4 o_normal;

void main() {
    o_position = vec4(v_position, 1.0);
    o_normal = vec4(normalize(v_normal), 0.0);
}
