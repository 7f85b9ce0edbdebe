#version 450 core
// SPDX-License-Identifier: MIT
// Light-view and cube-face G-buffers of dipole::DirpoleSubsurfaceProvider (the dirpole thesis §4.1, steps
// 1 and 2), vertex stage: world-space (mm) position and normal of the object.

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;

layout(location = 0) uniform mat4 u_clipFromWorld;

out vec3 v_position;
out vec3 v_normal;

void main() {
    v_position = a_position;
    v_normal = a_normal;
    gl_Position = u_clipFromWorld * vec4(a_position, 1.0);
}
