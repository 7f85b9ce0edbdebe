// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Private helpers shared by the painting operations (not part of the public API).

#include <lucent/material/MaterialVolume.h>
#include <lucent/material/Medium.h>

#include <algorithm>
#include <cmath>

namespace lucent::detail {

/// Clamp with NaN → 0, as sanitize() (Medium.h).
inline float clampOrZero(float v, float lo, float hi) {
    return std::isnan(v) ? 0.f : std::clamp(v, lo, hi);
}

/// sanitize() applied in place to voxel v of a brick's SoA data.
inline void sanitizeVoxel(float* data, int v) {
    constexpr int N = MaterialVolume::BRICK_VOXELS;
    for (int c = 0; c < 3; ++c) {
        float& st = data[(0 + c) * N + v];
        float& ss = data[(3 + c) * N + v];
        float& g = data[(6 + c) * N + v];
        st = clampOrZero(st, 0.f, SIGMA_MAX);
        ss = clampOrZero(ss, 0.f, st);
        g = clampOrZero(g, -G_MAX, G_MAX);
    }
}

/// sanitizeVoxel() on `count` consecutive voxels (x-contiguous) of a brick, plane by plane.
inline void sanitizeRow(float* data, int v0, int count) {
    constexpr int N = MaterialVolume::BRICK_VOXELS;
    for (int c = 0; c < 3; ++c) {
        float* st = data + (0 + c) * N + v0;
        float* ss = data + (3 + c) * N + v0;
        float* g = data + (6 + c) * N + v0;
        for (int x = 0; x < count; ++x) {
            st[x] = clampOrZero(st[x], 0.f, SIGMA_MAX);
            ss[x] = clampOrZero(ss[x], 0.f, st[x]);
            g[x] = clampOrZero(g[x], -G_MAX, G_MAX);
        }
    }
}

/// Component k (0..8, MaterialVolume::component order) of a sample.
inline float sampleComponent(const MaterialSample& s, int k) {
    return k < 3 ? s.sigma_t[k] : k < 6 ? s.sigma_s[k - 3] : s.g[k - 6];
}

/// Selected component indices of a channel mask; returns their count.
inline int selectedComponents(ChannelMask mask, int out[MaterialVolume::COMPONENTS]) {
    int n = 0;
    for (int k = 0; k < MaterialVolume::COMPONENTS; ++k) {
        const uint8_t bit = k < 3   ? uint8_t(Channel::SigmaT)
                            : k < 6 ? uint8_t(Channel::SigmaS)
                                    : uint8_t(Channel::G);
        if (mask & bit)
            out[n++] = k;
    }
    return n;
}

}  // namespace lucent::detail
