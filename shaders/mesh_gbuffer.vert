#version 450 core
// SPDX-License-Identifier: MIT
// G-buffer pass, vertex stage: world-space (mm) position and normal of the mesh.
#include "common/frame.glsl"

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;

out vec3 v_position;
out vec3 v_normal;

void main() {
    v_position = a_position;
    v_normal = a_normal;
    gl_Position = frame.clipFromWorld * vec4(a_position, 1.0);
}
