// SPDX-License-Identifier: MIT
/// @file
/// @brief boundarySkin: masked-out voxels next to the inside, valued by their inside neighbours.
#include <lucent/material/BoundarySkin.h>

#include <lucent/core/Parallel.h>
#include <lucent/material/MaterialVolume.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <optional>

namespace lucent {

namespace {

constexpr int B = MaterialVolume::BRICK;

}  // namespace

std::vector<uint8_t> bricksNearInside(const MaterialVolume& volume) {
    const int nb = volume.bricksPerAxis();
    std::vector<uint8_t> near(size_t(volume.brickCount()), 0);
    for (int b = 0; b < volume.brickCount(); ++b) {
        if (!volume.brickHasInside(b))
            continue;
        const Coord o = volume.brickOrigin(b);
        const int bx = o.x / B, by = o.y / B, bz = o.z / B;
        for (int z = std::max(bz - 1, 0); z <= std::min(bz + 1, nb - 1); ++z)
            for (int y = std::max(by - 1, 0); y <= std::min(by + 1, nb - 1); ++y)
                for (int x = std::max(bx - 1, 0); x <= std::min(bx + 1, nb - 1); ++x)
                    near[size_t(volume.brickIndexOf(Coord(x * B, y * B, z * B)))] = 1;
    }
    return near;
}

std::optional<MaterialSample> skinValue(const MaterialVolume& volume, const Coord& c) {
    const GridSpec& spec = volume.spec();
    if (volume.isInside(c))
        return std::nullopt;
    // The mixture of c's nearest inside neighbours: its face neighbours if it has any, else its
    // edge neighbours, else its corner ones.
    // Sums by ring: 1 face, 2 edge, 3 corner (the number of non-zero offsets).
    std::array<Rgb, 4> sigmaT{}, sigmaSReduced{}, sigmaS{}, sigmaSG{}, gSum{};
    std::array<int, 4> count{};
    // A ring whose voxels all hold one value gives that value exactly (an averaged one can
    // differ in the last bit): a homogeneous material stays homogeneous with its skin.
    std::array<MaterialSample, 4> first{};
    std::array<bool, 4> uniform{true, true, true, true};
    for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const int ring = std::abs(dx) + std::abs(dy) + std::abs(dz);
                const Coord q(c.x + dx, c.y + dy, c.z + dz);
                if (ring == 0 || !spec.contains(q) || !volume.isInside(q))
                    continue;
                const MaterialSample m = volume.at(q);
                if (count[ring] == 0)
                    first[ring] = m;
                else if (!(m == first[ring]))
                    uniform[ring] = false;
                sigmaT[ring] += m.sigma_t;
                sigmaSReduced[ring] += m.sigma_s;
                gSum[ring] += m.g;
                for (int ch = 0; ch < 3; ++ch) {
                    // Unreduced σs = σs′/(1−g) (mm⁻¹); |g| < 1 after sanitising.
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
        return std::nullopt;
    if (uniform[ring])
        return first[ring];
    const float inv = 1.f / float(count[ring]);
    MaterialSample mix;
    mix.sigma_t = sigmaT[ring] * inv;
    mix.sigma_s = sigmaSReduced[ring] * inv;
    for (int ch = 0; ch < 3; ++ch)
        mix.g[ch] =
            sigmaS[ring][ch] > 0.f ? sigmaSG[ring][ch] / sigmaS[ring][ch] : gSum[ring][ch] * inv;
    return mix;
}

std::vector<SkinVoxel> boundarySkin(const MaterialVolume& volume) {
    const GridSpec& spec = volume.spec();
    const int n = spec.resolution;
    // One list per z plane, filled in parallel and joined in order (so the result is sorted).
    std::vector<std::vector<SkinVoxel>> planes(static_cast<size_t>(n));
    const std::vector<uint8_t> nearInside = bricksNearInside(volume);
    parallelFor(0, n, [&](int64_t zBegin, int64_t zEnd) {
        for (int z = int(zBegin); z < int(zEnd); ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const Coord c(x, y, z);
                    if (!nearInside[size_t(volume.brickIndexOf(c))])
                        continue;
                    if (const std::optional<MaterialSample> mix = skinValue(volume, c))
                        planes[size_t(z)].push_back({spec.linearIndex(c), *mix});
                }
    });
    std::vector<SkinVoxel> skin;
    for (const std::vector<SkinVoxel>& plane : planes)
        skin.insert(skin.end(), plane.begin(), plane.end());
    return skin;
}

}  // namespace lucent
