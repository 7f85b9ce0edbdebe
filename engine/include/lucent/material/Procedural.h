// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Procedural fills of a MaterialVolume's interior: marble veins, turbulence and
/// skin-like layering by depth below the surface, plus the depth estimate they need.
///
///     ProceduralFill fill;
///     fill.pattern = ProceduralPattern::Marble;
///     fill.materialA = findPreset("marble").sample();
///     fill.materialB = veinSample;
///     fill.scale = 20.f;                                // mm per noise period
///     fillProcedural(vol, fill, &history);
///
/// Noise is Perlin's improved gradient noise (Perlin 2002, "Improving Noise", SIGGRAPH), with
/// a permutation seeded by `seed`; results depend only on the parameters, not on threads.

#include <lucent/core/Types.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/material/Medium.h>

#include <cstdint>
#include <vector>

namespace lucent {

class History;

enum class ProceduralPattern : uint8_t {
    Turbulence,  ///< f = turbulence(p / scale), blend A → B
    Marble,      ///< f = ½(1 + sin(2π (p·dir)/scale + amplitude·turbulence)), veins of B
    Layered,     ///< layers by depth below the surface (mm), optionally jittered by noise
};

/// One layer of a Layered fill: `thickness` mm of `material`; the last layer extends to the core.
struct MaterialLayer {
    float thickness = 1.f;  ///< mm, > 0
    MaterialSample material;
};

struct ProceduralFill {
    ProceduralPattern pattern = ProceduralPattern::Turbulence;
    MaterialSample materialA;  ///< f = 0
    MaterialSample materialB;  ///< f = 1
    float scale = 10.f;        ///< mm per noise period, (0, 1e5]
    int octaves = 5;           ///< turbulence octaves, [1, 12]
    float amplitude = 5.f;     ///< Marble: turbulence phase amplitude (radians); Layered: depth
                               ///< jitter (mm); ≥ 0
    float sharpness = 1.f;     ///< Marble: vein exponent f ← f^sharpness, [0.05, 100]
    Vector3f direction{1.f, 0.f, 0.f};  ///< Marble: stripe normal (normalised internally)
    std::vector<MaterialLayer> layers;  ///< Layered: from the surface inwards, ≥ 1
    uint64_t seed = 1;
    ChannelMask channels = ALL_CHANNELS;
};

/// Improved Perlin noise in about [−1, 1] at p (noise units), permutation from `seed`.
float gradientNoise(const Point3f& p, uint64_t seed);
/// Perlin turbulence Σ_{i<octaves} |noise(2^i p)| / 2^i, normalised to [0, 1].
float turbulence(const Point3f& p, int octaves, uint64_t seed);

/// Depth of every voxel centre below the surface of the inside mask, mm, x fastest: for inside
/// voxels (d − ½)·h, where d is the exact Euclidean distance in voxels from the centre to the
/// nearest outside voxel centre (the grid's exterior counts as outside); 0 for outside voxels.
std::vector<float> distanceToSurface(const MaterialVolume& volume);

/// Fills every inside voxel's selected channels with the pattern.
/// @throw ValueError naming the offending field.
void fillProcedural(MaterialVolume& volume, const ProceduralFill& fill, History* history = nullptr);

}  // namespace lucent
