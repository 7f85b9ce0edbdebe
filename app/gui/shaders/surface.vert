// SPDX-License-Identifier: MIT
// Mesh surface of the viewport: world-space (posed) position and normal, and the rest-space
// position at which surface.frag looks the material up.
#version 450 core
layout(location = 0) in vec3 a_position;  // mm, object rest space == world space
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_rest;      // rest-space position: where the material is
uniform mat4 u_clipFromWorld;
out vec3 v_world;
out vec3 v_normal;
out vec3 v_rest;
void main() {
    v_world = a_position;
    v_normal = a_normal;
    v_rest = a_rest;
    gl_Position = u_clipFromWorld * vec4(a_position, 1.0);
}
