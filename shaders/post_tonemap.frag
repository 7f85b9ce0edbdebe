#version 450 core
// SPDX-License-Identifier: MIT
// Tone map: linear HDR radiance → display values (exposure, curve, sRGB OETF), same maths as
// lucent::toneMapToDisplay.
#include "common/frame.glsl"
#include "common/tonemap.glsl"

layout(binding = 0) uniform sampler2D u_radiance;

in vec2 v_uv;
layout(location = 0) out vec4 o_display;

void main() {
    vec3 linear = texture(u_radiance, v_uv).rgb;
    o_display = vec4(lucentToneMap(linear, frame.toneMap.x, int(frame.toneMap.y + 0.5)), 1.0);
}
