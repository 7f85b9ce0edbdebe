// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The Fresnel reflectance of a smooth dielectric boundary: the one definition the path
/// tracer, SSLPV and the dipoles share (the tests' independent forward tracer keeps its own).

#include <algorithm>
#include <cmath>
#include <concepts>
#include <type_traits>

namespace lucent {

/// Exact unpolarised Fresnel reflectance of a smooth dielectric interface (Born & Wolf §1.5;
/// pbrt-v3 Eq. 8.1–8.2): the mean of the s and p reflectances.
/// @param cosI cosine of the angle of incidence on the incident side, in [0, 1] (clamped).
/// @param eta relative index η_transmitted / η_incident (> 0; otherwise 1 is returned).
/// @return R ∈ [0, 1]; 1 under total internal reflection. Float in, float arithmetic (the GL
/// shaders' precision); double in, double.
template <std::floating_point A, std::floating_point B>
[[nodiscard]] inline std::common_type_t<A, B> fresnelDielectric(A cosI, B eta) {
    using T = std::common_type_t<A, B>;
    const T c = std::clamp(T(cosI), T(0), T(1));
    const T e = T(eta);
    if (!(e > T(0)))
        return T(1);
    // Snell: sin θt = sin θi / η.
    const T sin2T = (T(1) - c * c) / (e * e);
    if (sin2T >= T(1))
        return T(1);  // total internal reflection
    const T cosT = std::sqrt(T(1) - sin2T);
    const T rs = (c - e * cosT) / (c + e * cosT);
    const T rp = (e * c - cosT) / (e * c + cosT);
    return std::clamp(T(0.5) * (rs * rs + rp * rp), T(0), T(1));
}

}  // namespace lucent
