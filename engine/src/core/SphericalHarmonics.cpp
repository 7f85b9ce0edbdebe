// SPDX-License-Identifier: MIT
#include <lucent/core/SphericalHarmonics.h>

#include <lucent/core/Error.h>

namespace lucent {

void shEvaluate(int order, const Vector3f& w, float* out) {
    LUCENT_ASSERT(order >= 0 && order <= 2);
    // Orthonormal real SH (Sloan, "Stupid Spherical Harmonics Tricks", Appendix A2).
    out[0] = 0.282094791773878f;  // 1/(2√π)
    if (order < 1)
        return;
    constexpr float k1 = 0.488602511902920f;  // √(3/(4π))
    out[1] = k1 * w.y;
    out[2] = k1 * w.z;
    out[3] = k1 * w.x;
    if (order < 2)
        return;
    constexpr float k2 = 1.092548430592079f;   // √(15/(4π))
    constexpr float k20 = 0.315391565252520f;  // √(5/(16π))
    constexpr float k22 = 0.546274215296040f;  // √(15/(16π))
    out[4] = k2 * w.x * w.y;
    out[5] = k2 * w.y * w.z;
    out[6] = k20 * (3.f * w.z * w.z - 1.f);
    out[7] = k2 * w.x * w.z;
    out[8] = k22 * (w.x * w.x - w.y * w.y);
}

float clampedCosineZonal(int l) {
    // ∫ max(0,cos θ) Y_l0 dω: √π/2, √(π/3), √(5π)/8 (the SSLPV project page errata errata;
    // Ramamoorthi & Hanrahan 2001).
    switch (l) {
        case 0:
            return 0.886226925452758f;  // √π/2
        case 1:
            return 1.023326707946489f;  // √(π/3)
        case 2:
            return 0.495415912200751f;  // √(5π)/8
        default:
            LUCENT_THROW(ValueError, "clampedCosineZonal: band ", l, " is not supported (l <= 2)");
    }
}

}  // namespace lucent
