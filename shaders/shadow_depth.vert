#version 450 core
// SPDX-License-Identifier: MIT
// Shadow pass: depth of the mesh seen from one light layer (spot, directional, or a cube face).

layout(location = 0) uniform mat4 u_clipFromWorld;
layout(location = 0) in vec3 a_position;

void main() {
    gl_Position = u_clipFromWorld * vec4(a_position, 1.0);
}
