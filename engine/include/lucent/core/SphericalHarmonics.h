// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Real spherical harmonics up to band l = 2 (9 coefficients).
///
/// Normalisation: orthonormal on the unit sphere, ∫ Y_lm Y_l'm' dω = δ. Ordering: flat index
/// i = l(l+1)+m, so [Y00, Y1-1, Y10, Y11, Y2-2, Y2-1, Y20, Y21, Y22] with
///   Y00 = 1/(2√π), Y1-1 = √(3/4π) y, Y10 = √(3/4π) z, Y11 = √(3/4π) x, ...
/// (the "Stupid SH tricks" / Filament convention; see docs/conventions.md).
///
///     ShCoeffs<2> lobe = clampedCosineLobe<2>(normal);     // projected max(0, n·ω)
///     float v = lobe.evaluate(direction);

#include <lucent/core/Types.h>

#include <array>
#include <cmath>

namespace lucent {

/// Number of coefficients for SH with bands 0..order (order 1 → 4, order 2 → 9).
constexpr int shCount(int order) {
    return (order + 1) * (order + 1);
}
/// Flat index of coefficient (l, m).
constexpr int shIndex(int l, int m) {
    return l * (l + 1) + m;
}

/// Evaluates all real SH basis functions of bands 0..order in unit direction `w`.
/// @param order 1 or 2. @param out receives shCount(order) values.
void shEvaluate(int order, const Vector3f& w, float* out);

/// Zonal coefficient of the clamped cosine max(0, cos θ) in band l (l ≤ 2), orthonormal basis.
/// Band 0: √π/2, band 1: √(π/3), band 2: √(5π)/8 (SSLPV errata, the SSLPV project page errata;
/// Ramamoorthi-Hanrahan).
float clampedCosineZonal(int l);

/// Henyey–Greenstein phase function moment for band l: its Legendre coefficient is g^l.
inline float hgMoment(float g, int l) {
    float r = 1.f;
    for (int i = 0; i < l; ++i)
        r *= g;
    return r;
}

/// Henyey–Greenstein phase function value (sr⁻¹) for cosine `cosTheta` between the incoming
/// propagation direction and the outgoing direction.
inline float hgPhase(float g, float cosTheta) {
    const float d = 1.f + g * g - 2.f * g * cosTheta;
    return INV_4PI * (1.f - g * g) / (d * std::sqrt(std::max(d, 1e-12f)));
}

/// SH coefficient vector of a fixed order (1 or 2).
template <int Order>
struct ShCoeffs {
    static constexpr int COUNT = shCount(Order);
    std::array<float, COUNT> c{};

    /// Value of the represented function in unit direction `w`.
    [[nodiscard]] float evaluate(const Vector3f& w) const {
        float y[COUNT];
        shEvaluate(Order, w, y);
        float s = 0.f;
        for (int i = 0; i < COUNT; ++i)
            s += c[i] * y[i];
        return s;
    }
    ShCoeffs& operator+=(const ShCoeffs& o) {
        for (int i = 0; i < COUNT; ++i)
            c[i] += o.c[i];
        return *this;
    }
    ShCoeffs& operator*=(float s) {
        for (float& v : c)
            v *= s;
        return *this;
    }
};

/// Rotates a zonal (axially symmetric about +z) function with zonal coefficients `zonal[l]`
/// so its axis points along unit `axis`: c_lm = √(4π/(2l+1)) · z_l · Y_lm(axis).
template <int Order>
ShCoeffs<Order> rotateZonal(const float* zonal, const Vector3f& axis) {
    ShCoeffs<Order> r;
    float y[shCount(Order)];
    shEvaluate(Order, axis, y);
    for (int l = 0; l <= Order; ++l) {
        const float k = std::sqrt(4.f * PI / float(2 * l + 1)) * zonal[l];
        for (int m = -l; m <= l; ++m)
            r.c[shIndex(l, m)] = k * y[shIndex(l, m)];
    }
    return r;
}

/// The clamped cosine lobe max(0, axis·ω) projected on SH of the given order.
template <int Order>
ShCoeffs<Order> clampedCosineLobe(const Vector3f& axis) {
    float z[3] = {clampedCosineZonal(0), clampedCosineZonal(1), clampedCosineZonal(2)};
    return rotateZonal<Order>(z, axis);
}

/// Projects a function on the sphere onto SH by numerical quadrature (Fibonacci sphere of
/// `samples` points). Intended for tests and start-up precomputation, not hot loops.
/// @param f callable float(const Vector3f&).
template <int Order, typename F>
ShCoeffs<Order> shProject(F&& f, int samples = 20000) {
    ShCoeffs<Order> r;
    float y[shCount(Order)];
    const float golden = PI * (3.f - std::sqrt(5.f));
    const double w = 4.0 * PI / samples;
    double acc[shCount(Order)] = {};
    for (int i = 0; i < samples; ++i) {
        const float z = 1.f - (2.f * i + 1.f) / samples;
        const float rad = std::sqrt(std::max(0.f, 1.f - z * z));
        const float phi = golden * i;
        const Vector3f d(rad * std::cos(phi), rad * std::sin(phi), z);
        const float v = f(d);
        shEvaluate(Order, d, y);
        for (int k = 0; k < shCount(Order); ++k)
            acc[k] += double(v) * y[k];
    }
    for (int k = 0; k < shCount(Order); ++k)
        r.c[k] = float(acc[k] * w);
    return r;
}

/// Energy per band: Σ_m c_lm² for band l (rotation invariant).
template <int Order>
float shBandEnergy(const ShCoeffs<Order>& s, int l) {
    float e = 0.f;
    for (int m = -l; m <= l; ++m)
        e += s.c[shIndex(l, m)] * s.c[shIndex(l, m)];
    return e;
}

}  // namespace lucent
