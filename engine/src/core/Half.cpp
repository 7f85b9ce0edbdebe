// SPDX-License-Identifier: MIT
#include <lucent/core/Half.h>

#include <cmath>
#include <cstring>

namespace lucent {

uint16_t floatToHalf(float value) {
    uint32_t x;
    std::memcpy(&x, &value, sizeof(x));
    const uint32_t sign = (x >> 16) & 0x8000u;
    uint32_t mant = x & 0x7fffffu;
    const int exp = int((x >> 23) & 0xffu);
    if (exp == 255)
        return uint16_t(sign | 0x7c00u | (mant ? 0x200u : 0u));  // Inf / NaN
    const int e = exp - 127 + 15;
    if (e >= 31)
        return uint16_t(sign | 0x7c00u);  // overflow → Inf
    if (e <= 0) {                         // subnormal half (or zero)
        if (e < -10)
            return uint16_t(sign);
        mant |= 0x800000u;
        const int shift = 14 - e;
        uint32_t h = mant >> shift;
        const uint32_t rem = mant & ((1u << shift) - 1u), halfway = 1u << (shift - 1);
        if (rem > halfway || (rem == halfway && (h & 1u)))
            ++h;
        return uint16_t(sign | h);
    }
    uint32_t h = (uint32_t(e) << 10) | (mant >> 13);
    const uint32_t rem = mant & 0x1fffu;
    if (rem > 0x1000u || (rem == 0x1000u && (h & 1u)))
        ++h;  // carry may round up to Inf: correct
    return uint16_t(sign | h);
}

float halfToFloat(uint16_t bits) {
    const uint32_t sign = uint32_t(bits & 0x8000u) << 16;
    const uint32_t exp = (bits >> 10) & 0x1fu;
    const uint32_t mant = bits & 0x3ffu;
    float out;
    if (exp == 0) {
        out = std::ldexp(float(mant), -24);  // zero or subnormal
        return sign ? -out : out;
    }
    const uint32_t f = exp == 31 ? (sign | 0x7f800000u | (mant << 13))
                                 : (sign | ((exp - 15 + 127) << 23) | (mant << 13));
    std::memcpy(&out, &f, sizeof(out));
    return out;
}

}  // namespace lucent
