// SPDX-License-Identifier: MIT
// Unpolarised dielectric Fresnel reflectance, GLSL mirror of lucent::dipole::fresnelReflectance
// (engine/src/dipole/Profiles.cpp; Fresnel equations, e.g. pbrt-v4 §9.3 Eq. 9.6).
#pragma once

// F_r for light arriving from outside at cos θ_i ∈ [0, 1] on a medium of relative index eta.
float dipoleFresnelReflectance(float cosThetaI, float eta) {
    float ci = clamp(cosThetaI, 0.0, 1.0);
    float sin2T = (1.0 - ci * ci) / (eta * eta);
    if (sin2T >= 1.0) return 1.0;
    float ct = sqrt(1.0 - sin2T);
    float rs = (ci - eta * ct) / (ci + eta * ct);
    float rp = (eta * ci - ct) / (eta * ci + ct);
    return 0.5 * (rs * rs + rp * rp);
}
