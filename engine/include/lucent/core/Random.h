// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Seeded random numbers and low-discrepancy sequences.
///
///     Pcg32 rng(pixelSeed(x, y, frame, seed));
///     float u = rng.uniform();                 // [0, 1)
///     Point2f p = r2Sequence(i);                // rank-1 lattice / R2 sequence
/// Every stream is a pure function of its seed, so results do not depend on thread count.

#include <lucent/core/Types.h>

#include <cstdint>

namespace lucent {

/// PCG32 (O'Neill 2014, pcg32_random_r): 64-bit state, 32-bit output, selectable stream.
class Pcg32 {
public:
    explicit Pcg32(uint64_t seed = 0x853c49e6748fea9bULL, uint64_t stream = 0xda3e39cb94b95bdbULL) {
        seedWith(seed, stream);
    }
    void seedWith(uint64_t seed, uint64_t stream) {
        m_state = 0u;
        m_inc = (stream << 1u) | 1u;
        nextUint();
        m_state += seed;
        nextUint();
    }
    uint32_t nextUint() {
        const uint64_t old = m_state;
        m_state = old * 6364136223846793005ULL + m_inc;
        const auto xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
        const auto rot = uint32_t(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31u));
    }
    /// Uniform float in [0, 1): 24 random mantissa bits, never returns 1.
    float uniform() { return float(nextUint() >> 8) * 0x1p-24f; }
    /// Uniform integer in [0, bound).
    uint32_t uniformBelow(uint32_t bound) { return uint32_t((uint64_t(nextUint()) * bound) >> 32); }

private:
    uint64_t m_state = 0;
    uint64_t m_inc = 0;
};

/// 64-bit mix (SplitMix64 finaliser) for deriving independent seeds.
constexpr uint64_t mixBits(uint64_t v) {
    v ^= v >> 31;
    v *= 0x7fb5d329728ea185ULL;
    v ^= v >> 27;
    v *= 0x81dadef4bc2dd44dULL;
    v ^= v >> 33;
    return v;
}

/// Deterministic seed for a pixel and sample index: independent of scheduling and threads.
constexpr uint64_t pixelSeed(uint32_t x, uint32_t y, uint32_t sampleIndex, uint64_t seed) {
    return mixBits(seed ^ mixBits((uint64_t(x) << 32 | y) ^ mixBits(uint64_t(sampleIndex) + 1)));
}

/// Radical inverse in base 2 (van der Corput), exact for 32-bit indices.
inline float radicalInverse2(uint32_t i) {
    i = (i << 16u) | (i >> 16u);
    i = ((i & 0x55555555u) << 1u) | ((i & 0xAAAAAAAAu) >> 1u);
    i = ((i & 0x33333333u) << 2u) | ((i & 0xCCCCCCCCu) >> 2u);
    i = ((i & 0x0F0F0F0Fu) << 4u) | ((i & 0xF0F0F0F0u) >> 4u);
    i = ((i & 0x00FF00FFu) << 8u) | ((i & 0xFF00FF00u) >> 8u);
    return float(i) * 0x1p-32f;
}

/// Hammersley point i of n in [0,1)².
inline Point2f hammersley(uint32_t i, uint32_t n) {
    return {(float(i) + 0.5f) / float(n), radicalInverse2(i)};
}

/// R2 sequence (Roberts 2018, generalised golden ratio): low discrepancy, open-ended.
inline Point2f r2Sequence(uint32_t i, Point2f offset = Point2f(0.5f)) {
    constexpr double a1 = 0.7548776662466927;  // 1/φ₂
    constexpr double a2 = 0.5698402909980532;  // 1/φ₂²
    const double x = offset.x + a1 * double(i);
    const double y = offset.y + a2 * double(i);
    return {float(x - std::floor(x)), float(y - std::floor(y))};
}

/// Halton sequence value of index i in a prime base.
float halton(uint32_t i, uint32_t base);

}  // namespace lucent
