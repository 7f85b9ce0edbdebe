// SPDX-License-Identifier: MIT
// Shadow-map lookups: one 2-D array layer per spot/directional light, six (cube faces +x −x +y
// −y +z −z, 90° perspective views) per point light. Depth comparison through
// sampler2DArrayShadow (hardware 2×2 PCF) on a 3×3 tap grid.
#pragma once
#include "shared/LightingShared.h"

layout(std430, binding = LUCENT_BINDING_SHADOW_LAYERS) readonly buffer ShadowLayerBlock {
    GpuShadowLayer shadowLayers[];
};

// Fraction of the light that reaches world point p (mm) with unit normal n, in [0, 1].
// Bias: the lookup point is pushed along n by 1.5 shadow texels (normal-offset bias) on top of
// the slope-scaled polygon offset applied when the depth was rendered.
float shadowVisibility(sampler2DArrayShadow maps, GpuLight light, vec3 p, vec3 n) {
    int layer = light.shadow.x;
    if (layer < 0) return 1.0;
    if (light.shadow.y == 6) {
        vec3 d = p - light.positionType.xyz;
        vec3 a = abs(d);
        int face = (a.x >= a.y && a.x >= a.z) ? (d.x >= 0.0 ? 0 : 1)
                 : (a.y >= a.z ? (d.y >= 0.0 ? 2 : 3) : (d.z >= 0.0 ? 4 : 5));
        layer += face;
    }
    GpuShadowLayer sl = shadowLayers[layer];
    float texel = sl.params.x > 0.5 ? sl.params.y
                                    : sl.params.y * distance(p, light.positionType.xyz);
    vec3 q = p + n * (1.5 * texel);
    vec4 c = sl.clipFromWorld * vec4(q, 1.0);
    if (c.w <= 0.0) return 1.0;
    vec3 uvz = c.xyz / c.w * 0.5 + 0.5;
    if (uvz.z >= 1.0) return 1.0;
    vec2 texelUv = 1.0 / vec2(textureSize(maps, 0).xy);
    float sum = 0.0;
    for (int y = -1; y <= 1; ++y)
        for (int x = -1; x <= 1; ++x)
            sum += texture(maps, vec4(uvz.xy + vec2(x, y) * texelUv, float(layer), uvz.z));
    return sum / 9.0;
}
