#version 450 core
// SPDX-License-Identifier: MIT
// App overlay (owner: app; app/gui/PreviewPasses.cpp): the brush cursor drawn over the tone-mapped
// preview with post_fullscreen.vert and alpha blending. A ring where the surface is at the
// brush radius from the cursor centre, a faint tint inside it. Units: mm.

layout(binding = 0) uniform sampler2D u_position;  // G-buffer: rgb world position, a coverage

uniform vec4 u_brush;  // xyz cursor centre (mm), w radius (mm) > 0

in vec2 v_uv;
layout(location = 0) out vec4 o_color;

void main() {
    ivec2 size = textureSize(u_position, 0);  // G-buffer may be smaller (reduced resolution)
    vec4 p = texelFetch(u_position, clamp(ivec2(v_uv * vec2(size)), ivec2(0), size - 1), 0);
    if (p.a < 0.5)
        discard;
    float d = length(p.xyz - u_brush.xyz);
    float w = u_brush.w * 0.06 + 0.02;  // ring half-width, mm
    if (abs(d - u_brush.w) < w)
        o_color = vec4(1.0, 0.85, 0.2, 0.85);
    else if (d < u_brush.w)
        o_color = vec4(1.0, 0.9, 0.5, 0.12);
    else
        discard;
}
