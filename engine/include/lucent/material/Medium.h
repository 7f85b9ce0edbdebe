// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The one material mapping every method shares (docs/conventions.md, docs/reference.md).
///
/// Painted parameters per RGB channel: σt = σa + σs′ (reduced extinction, mm⁻¹), σs′ (reduced
/// scattering, mm⁻¹, 0 ≤ σs′ ≤ σt) and g ∈ [−0.99, 0.99]. Transport methods that need the
/// unreduced medium use
///     σa = σt − σs′,   σs = σs′ / (1 − g),   σ_t,full = σa + σs.
/// Near g → 1 the denominator is clamped: 1 − g ≥ 0.01 (g is clamped to 0.99 at painting time).

#include <lucent/core/Types.h>

namespace lucent {

inline constexpr float G_MAX = 0.99f;
inline constexpr float SIGMA_MAX = 1e6f;  ///< largest coefficient accepted anywhere, mm⁻¹

/// Painted parameters of one voxel (reduced form).
struct MaterialSample {
    Rgb sigma_t{0.f};  ///< reduced extinction σa + σs′, mm⁻¹
    Rgb sigma_s{0.f};  ///< reduced scattering σs′, mm⁻¹
    Rgb g{0.f};        ///< HG asymmetry

    bool operator==(const MaterialSample&) const = default;
};

/// Unreduced medium coefficients for a path tracer (per channel, mm⁻¹).
struct MediumCoefficients {
    Rgb sigma_a{0.f};
    Rgb sigma_s{0.f};  ///< full (unreduced) scattering σs = σs′/(1−g)
    Rgb sigma_t{0.f};  ///< σa + σs
    Rgb g{0.f};
};

/// Clamps a sample into the valid domain: σt ∈ [0, SIGMA_MAX], 0 ≤ σs′ ≤ σt, |g| ≤ 0.99;
/// NaN becomes 0.
MaterialSample sanitize(const MaterialSample& s);

/// σa = σt − σs′, σs = σs′/(1−g) (with 1−g ≥ 1−G_MAX), σt,full = σa + σs.
inline MediumCoefficients toMedium(const MaterialSample& s) {
    MediumCoefficients m;
    m.sigma_a = glm::max(s.sigma_t - s.sigma_s, Rgb(0.f));
    m.g = glm::clamp(s.g, Rgb(-G_MAX), Rgb(G_MAX));
    m.sigma_s = s.sigma_s / (Rgb(1.f) - m.g);
    m.sigma_t = m.sigma_a + m.sigma_s;
    return m;
}

/// Single-scattering albedo of the reduced medium, σs′/σt (0 where σt = 0).
inline Rgb reducedAlbedo(const MaterialSample& s) {
    Rgb a;
    for (int c = 0; c < 3; ++c)
        a[c] = s.sigma_t[c] > 0.f ? s.sigma_s[c] / s.sigma_t[c] : 0.f;
    return a;
}

}  // namespace lucent
