// SPDX-License-Identifier: MIT
/// @file
/// @brief boundarySkin: masked-out voxels next to the inside, valued by their inside neighbours.
#include <lucent/material/BoundarySkin.h>

#include <lucent/core/Parallel.h>
#include <lucent/material/MaterialVolume.h>

#include <algorithm>
#include <array>
#include <cstdlib>

namespace lucent {

std::vector<SkinVoxel> boundarySkin(const MaterialVolume& volume) {
    const GridSpec& spec = volume.spec();
    const int n = spec.resolution;
    constexpr int B = MaterialVolume::BRICK;
    // One list per z plane, filled in parallel and joined in order (so the result is sorted).
    std::vector<std::vector<SkinVoxel>> planes(static_cast<size_t>(n));
    parallelFor(0, n, [&](int64_t zBegin, int64_t zEnd) {
        for (int z = int(zBegin); z < int(zEnd); ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const Coord c(x, y, z);
                    if (volume.isInside(c))
                        continue;
                    // Skip voxels whose neighbourhood touches no brick with an inside voxel
                    // (most of the empty space around an object), before the 26 lookups.
                    bool nearInside = false;
                    for (int bz = std::max(z - 1, 0) / B; bz <= std::min(z + 1, n - 1) / B; ++bz)
                        for (int by = std::max(y - 1, 0) / B; by <= std::min(y + 1, n - 1) / B;
                             ++by)
                            for (int bx = std::max(x - 1, 0) / B; bx <= std::min(x + 1, n - 1) / B;
                                 ++bx)
                                nearInside =
                                    nearInside || volume.brickHasInside(volume.brickIndexOf(
                                                      Coord(bx * B, by * B, bz * B)));
                    if (!nearInside)
                        continue;
                    // Inside neighbours by ring: 1 face, 2 edge, 3 corner (non-zero offsets).
                    std::array<Rgb, 4> sigmaT{}, sigmaSReduced{}, sigmaS{}, sigmaSG{}, gSum{};
                    std::array<int, 4> count{};
                    for (int dz = -1; dz <= 1; ++dz)
                        for (int dy = -1; dy <= 1; ++dy)
                            for (int dx = -1; dx <= 1; ++dx) {
                                const int ring = std::abs(dx) + std::abs(dy) + std::abs(dz);
                                const Coord q(x + dx, y + dy, z + dz);
                                if (ring == 0 || !spec.contains(q) || !volume.isInside(q))
                                    continue;
                                const MaterialSample m = volume.at(q);
                                sigmaT[ring] += m.sigma_t;
                                sigmaSReduced[ring] += m.sigma_s;
                                gSum[ring] += m.g;
                                for (int ch = 0; ch < 3; ++ch) {
                                    // Unreduced σs = σs′/(1−g); |g| < 1 after sanitising.
                                    const float s = m.sigma_s[ch] / (1.f - m.g[ch]);
                                    sigmaS[ring][ch] += s;
                                    sigmaSG[ring][ch] += s * m.g[ch];
                                }
                                ++count[ring];
                            }
                    int ring = 1;
                    while (ring <= 3 && count[ring] == 0)
                        ++ring;
                    if (ring > 3)
                        continue;
                    const float inv = 1.f / float(count[ring]);
                    SkinVoxel s;
                    s.index = spec.linearIndex(c);
                    s.value.sigma_t = sigmaT[ring] * inv;
                    s.value.sigma_s = sigmaSReduced[ring] * inv;
                    for (int ch = 0; ch < 3; ++ch)
                        s.value.g[ch] = sigmaS[ring][ch] > 0.f
                                            ? sigmaSG[ring][ch] / sigmaS[ring][ch]
                                            : gSum[ring][ch] * inv;
                    planes[size_t(z)].push_back(s);
                }
    });
    std::vector<SkinVoxel> skin;
    for (const std::vector<SkinVoxel>& plane : planes)
        skin.insert(skin.end(), plane.begin(), plane.end());
    return skin;
}

}  // namespace lucent
