// SPDX-License-Identifier: MIT
// Display mapping identical to lucent::toneMapToDisplay (engine/src/core/Image.cpp): exposure,
// curve (clamp, Reinhard x/(1+x), ACES fit of Narkowicz 2015), then the sRGB OETF
// (IEC 61966-2-1).
#pragma once
#include "shared/LightingShared.h"

float lucentSrgbOetf(float v) {
    v = clamp(v, 0.0, 1.0);
    return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

float lucentAcesFit(float x) {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

vec3 lucentToneMap(vec3 linear, float exposure, int curve) {
    vec3 outc;
    for (int c = 0; c < 3; ++c) {
        float v = linear[c];
        v = (isnan(v) || isinf(v)) ? 0.0 : max(v, 0.0) * exposure;
        if (curve == LUCENT_TONEMAP_REINHARD) v = v / (1.0 + v);
        else if (curve == LUCENT_TONEMAP_ACES) v = lucentAcesFit(v);
        outc[c] = lucentSrgbOetf(v);
    }
    return outc;
}
