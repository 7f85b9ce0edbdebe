// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Small helpers shared by the material tests.

#include <lucent/material/MaterialVolume.h>

#include <cstring>
#include <vector>

namespace lucent::test {

/// A cubic grid at the origin with 1 mm voxels.
inline GridSpec unitGrid(int n) {
    GridSpec s;
    s.origin = Point3f(0.f);
    s.voxelSize = 1.f;
    s.resolution = n;
    return s;
}

inline MaterialSample makeSample(Rgb st, Rgb ss, Rgb g) {
    return {st, ss, g};
}

/// Every float of every brick, in storage order (for bit-exact comparisons).
inline std::vector<float> rawBricks(const MaterialVolume& v) {
    const size_t per = size_t(MaterialVolume::BRICK_VOXELS) * MaterialVolume::COMPONENTS;
    std::vector<float> out(size_t(v.brickCount()) * per);
    for (int b = 0; b < v.brickCount(); ++b)
        std::memcpy(&out[size_t(b) * per], v.brickData(b), per * sizeof(float));
    return out;
}

inline bool bitEqual(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

/// Inside mask of a ball of `radius` voxels centred in the grid.
inline std::vector<uint8_t> ballMask(int n, float radius) {
    std::vector<uint8_t> m(size_t(n) * n * n, 0);
    const float c = 0.5f * float(n);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const float dx = x + 0.5f - c, dy = y + 0.5f - c, dz = z + 0.5f - c;
                m[(size_t(z) * n + y) * n + x] = dx * dx + dy * dy + dz * dz < radius * radius;
            }
    return m;
}

}  // namespace lucent::test
