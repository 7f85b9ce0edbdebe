// SPDX-License-Identifier: MIT
// Direct lighting from point, spot and directional lights: irradiance and the opaque surface
// BRDF (Lambert + normalised Blinn-Phong). Units: mm, W/sr, W/mm², W/(mm²·sr).
#pragma once
#include "shared/LightingShared.h"

const float LUCENT_PI = 3.14159265358979;

layout(std430, binding = LUCENT_BINDING_LIGHTS) readonly buffer LightBlock {
    GpuLight lights[];
};

// Incident direction (unit, from the surface toward the light) and irradiance on a surface
// facing the light, E⊥ (W/mm²), at world point p (mm).
// Point/spot: E⊥ = I(ω) / d², the inverse-square law for an isotropic point source
// (pbrt-v4 §4.1.2, E = I cosθ / r²; the cosθ is applied by the caller).
// Spot falloff: smoothstep between the outer and inner cone cosines, as documented on
// lucent::Light::intensityToward (lucent/scene/Scene.h).
// Directional: E⊥ is the light's irradiance itself.
void lightIncidence(GpuLight light, vec3 p, out vec3 wi, out vec3 irradiance, out float dist) {
    int type = int(light.positionType.w);
    if (type == LUCENT_LIGHT_DIRECTIONAL) {
        wi = -normalize(light.directionCosOuter.xyz);
        irradiance = light.intensityCosInner.rgb;
        dist = 1e30;
        return;
    }
    vec3 d = light.positionType.xyz - p;
    float d2 = max(dot(d, d), 1e-12);
    dist = sqrt(d2);
    wi = d / dist;
    vec3 intensity = light.intensityCosInner.rgb;
    if (type == LUCENT_LIGHT_SPOT) {
        float cosAngle = dot(-wi, normalize(light.directionCosOuter.xyz));
        intensity *= smoothstep(light.directionCosOuter.w, light.intensityCosInner.w, cosAngle);
    }
    irradiance = intensity / d2;
}

// BRDF times cosθ_i for unit normal n, view direction v (toward the eye) and light direction wi.
// Lambert: f_d = ρ_d / π (pbrt-v4 §9.2, DiffuseBxDF: f = R/π).
// Normalised Blinn-Phong: f_s = ρ_s (m + 8) / (8π) (n·h)^m (Akenine-Möller, Haines, Hoffman,
// Real-Time Rendering 3rd ed., Eq. 7.49), energy-normalised so ρ_s is the lobe's albedo.
vec3 surfaceBrdfCos(GpuSurface s, vec3 n, vec3 v, vec3 wi, bool specular) {
    float cosI = dot(n, wi);
    if (cosI <= 0.0) return vec3(0.0);
    vec3 f = s.diffuse.rgb / LUCENT_PI;
    if (specular) {
        float m = max(s.specularShininess.w, 1.0);
        vec3 h = normalize(wi + v);
        f += s.specularShininess.rgb * ((m + 8.0) / (8.0 * LUCENT_PI)) * pow(max(dot(n, h), 0.0), m);
    }
    return f * cosI;
}
