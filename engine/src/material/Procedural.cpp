// SPDX-License-Identifier: MIT
/// @file
/// @brief Gradient noise, turbulence, the inside-mask distance transform and procedural fills
/// (Procedural.h).
#include <lucent/material/Procedural.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Random.h>
#include <lucent/material/History.h>

#include "BrushOps.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace lucent {

using detail::sampleComponent;
using detail::sanitizeVoxel;
using detail::selectedComponents;

namespace {

/// Improved Perlin noise (Perlin 2002, "Improving Noise", SIGGRAPH; reference implementation
/// at mrl.nyu.edu/~perlin/noise): quintic fade, 12 edge gradients, a seeded permutation.
class PerlinNoise {
public:
    explicit PerlinNoise(uint64_t seed) {
        std::array<uint8_t, 256> p{};
        for (int i = 0; i < 256; ++i)
            p[size_t(i)] = uint8_t(i);
        Pcg32 rng(mixBits(seed), 0x5eed);
        for (int i = 255; i > 0; --i)
            std::swap(p[size_t(i)], p[rng.uniformBelow(uint32_t(i) + 1)]);
        for (int i = 0; i < 512; ++i)
            m_perm[size_t(i)] = p[size_t(i & 255)];
    }

    float operator()(float x, float y, float z) const {
        const float fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
        const int X = int(int64_t(fx) & 255), Y = int(int64_t(fy) & 255),
                  Z = int(int64_t(fz) & 255);
        x -= fx;
        y -= fy;
        z -= fz;
        const float u = fade(x), v = fade(y), w = fade(z);
        const auto& P = m_perm;
        const int A = P[size_t(X)] + Y, AA = P[size_t(A)] + Z, AB = P[size_t(A) + 1] + Z;
        const int B = P[size_t(X) + 1] + Y, BA = P[size_t(B)] + Z, BB = P[size_t(B) + 1] + Z;
        return lerp(
            w,
            lerp(v, lerp(u, grad(P[size_t(AA)], x, y, z), grad(P[size_t(BA)], x - 1, y, z)),
                 lerp(u, grad(P[size_t(AB)], x, y - 1, z), grad(P[size_t(BB)], x - 1, y - 1, z))),
            lerp(v,
                 lerp(u, grad(P[size_t(AA) + 1], x, y, z - 1),
                      grad(P[size_t(BA) + 1], x - 1, y, z - 1)),
                 lerp(u, grad(P[size_t(AB) + 1], x, y - 1, z - 1),
                      grad(P[size_t(BB) + 1], x - 1, y - 1, z - 1))));
    }

    /// Perlin 1985 ("An Image Synthesizer", SIGGRAPH, Sec. 4 turbulence):
    /// Σ_{i<octaves} |noise(2^i p)| / 2^i, divided by Σ 2^−i so the result lies in [0, 1].
    float turbulence(const Point3f& p, int octaves) const {
        float sum = 0.f, norm = 0.f, f = 1.f;
        for (int i = 0; i < octaves; ++i) {
            sum += std::abs((*this)(p.x * f, p.y * f, p.z * f)) / f;
            norm += 1.f / f;
            f *= 2.f;
        }
        return std::clamp(sum / norm, 0.f, 1.f);
    }

private:
    // Perlin 2002, Eq. (fade): 6t⁵ − 15t⁴ + 10t³.
    static float fade(float t) { return t * t * t * (t * (t * 6.f - 15.f) + 10.f); }
    static float lerp(float t, float a, float b) { return a + t * (b - a); }
    static float grad(int hash, float x, float y, float z) {
        const int h = hash & 15;
        const float u = h < 8 ? x : y;
        const float v = h < 4 ? y : (h == 12 || h == 14) ? x : z;
        return ((h & 1) == 0 ? u : -u) + ((h & 2) == 0 ? v : -v);
    }
    std::array<int, 512> m_perm{};
};

/// 1-D squared Euclidean distance transform of f (Felzenszwalb & Huttenlocher 2012, "Distance
/// Transforms of Sampled Functions", Theory of Computing 8, Algorithm 1: lower envelope of the
/// parabolas q ↦ (q − p)² + f(p)). d, v, z are scratch buffers of f.size() (+1 for z).
void edt1d(const std::vector<double>& f, std::vector<double>& d, std::vector<int>& v,
           std::vector<double>& z) {
    const int n = int(f.size());
    int k = 0;
    v[0] = 0;
    z[0] = -std::numeric_limits<double>::infinity();
    z[1] = std::numeric_limits<double>::infinity();
    auto intersect = [&](int q, int p) {
        return ((f[size_t(q)] + double(q) * q) - (f[size_t(p)] + double(p) * p)) /
               (2.0 * q - 2.0 * p);
    };
    for (int q = 1; q < n; ++q) {
        double s = intersect(q, v[size_t(k)]);
        while (s <= z[size_t(k)]) {  // z[0] = −∞ stops the loop at k = 0
            --k;
            s = intersect(q, v[size_t(k)]);
        }
        ++k;
        v[size_t(k)] = q;
        z[size_t(k)] = s;
        z[size_t(k) + 1] = std::numeric_limits<double>::infinity();
    }
    k = 0;
    for (int q = 0; q < n; ++q) {
        while (z[size_t(k) + 1] < q)
            ++k;
        const double dq = double(q) - v[size_t(k)];
        d[size_t(q)] = dq * dq + f[size_t(v[size_t(k)])];
    }
}

void checkMaterial(const MaterialSample& s, const char* field) {
    for (int k = 0; k < MaterialVolume::COMPONENTS; ++k) {
        const float u = sampleComponent(s, k);
        LUCENT_CHECK(std::isfinite(u), "fillProcedural: ", field, " component ", k,
                     " is NaN or infinite");
        if (k < 6)
            LUCENT_CHECK(u >= 0.f && u <= SIGMA_MAX, "fillProcedural: ", field, " component ", k,
                         " = ", u, " mm^-1 must be in [0, ", SIGMA_MAX, "]");
        else
            LUCENT_CHECK(std::abs(u) <= G_MAX, "fillProcedural: ", field, ".g = ", u,
                         " must be in [-", G_MAX, ", ", G_MAX, "]");
    }
}

void validateFill(const ProceduralFill& f) {
    LUCENT_CHECK(uint8_t(f.pattern) <= uint8_t(ProceduralPattern::Layered),
                 "fillProcedural: pattern = ", int(f.pattern), " is not a ProceduralPattern");
    LUCENT_CHECK(std::isfinite(f.scale) && f.scale > 0.f && f.scale <= 1e5f,
                 "fillProcedural: scale = ", f.scale, " mm must be in (0, 1e5]");
    LUCENT_CHECK(f.octaves >= 1 && f.octaves <= 12, "fillProcedural: octaves = ", f.octaves,
                 " must be in [1, 12]");
    LUCENT_CHECK(std::isfinite(f.amplitude) && f.amplitude >= 0.f && f.amplitude <= 1e5f,
                 "fillProcedural: amplitude = ", f.amplitude, " must be in [0, 1e5]");
    LUCENT_CHECK(std::isfinite(f.sharpness) && f.sharpness >= 0.05f && f.sharpness <= 100.f,
                 "fillProcedural: sharpness = ", f.sharpness, " must be in [0.05, 100]");
    LUCENT_CHECK(f.channels != 0 && (f.channels & ~ALL_CHANNELS) == 0,
                 "fillProcedural: channels = ", int(f.channels),
                 " must be a nonzero combination of SigmaT=1, SigmaS=2, G=4");
    if (f.pattern == ProceduralPattern::Layered) {
        LUCENT_CHECK(!f.layers.empty(), "fillProcedural: a Layered fill needs at least one layer");
        for (size_t i = 0; i < f.layers.size(); ++i) {
            LUCENT_CHECK(std::isfinite(f.layers[i].thickness) && f.layers[i].thickness > 0.f,
                         "fillProcedural: layers[", i, "].thickness = ", f.layers[i].thickness,
                         " mm must be finite and > 0");
            checkMaterial(f.layers[i].material, "layers[].material");
        }
    } else {
        checkMaterial(f.materialA, "materialA");
        checkMaterial(f.materialB, "materialB");
    }
    if (f.pattern == ProceduralPattern::Marble)
        LUCENT_CHECK(isFinite(f.direction) && glm::length(f.direction) > 1e-6f,
                     "fillProcedural: direction must be finite and nonzero");
}

}  // namespace

float gradientNoise(const Point3f& p, uint64_t seed) {
    return PerlinNoise(seed)(p.x, p.y, p.z);
}

float turbulence(const Point3f& p, int octaves, uint64_t seed) {
    LUCENT_CHECK(octaves >= 1 && octaves <= 12, "turbulence: octaves = ", octaves,
                 " must be in [1, 12]");
    return PerlinNoise(seed).turbulence(p, octaves);
}

std::vector<float> distanceToSurface(const MaterialVolume& volume) {
    LUCENT_CHECK(volume.brickCount() > 0, "distanceToSurface: the material volume is empty");
    const int n = volume.resolution();
    const GridSpec& spec = volume.spec();
    const std::vector<uint8_t>& inside = volume.insideMask();
    // Squared distances, separable over x, y, z. The grid is padded by one outside voxel on each
    // side of every row (index 0 and n+1), so the exterior of the grid counts as outside.
    std::vector<float> d2(spec.voxelCount());
    const double BIG = 1e20;  // "infinity" of F&H; finite so the envelope arithmetic is exact
    const int m = n + 2;
    auto pass = [&](int axis) {
        parallelFor(
            0, int64_t(n) * n,
            [&](int64_t begin, int64_t end) {
                const size_t len = size_t(m);
                std::vector<double> f(len), d(len), z(len + 1);
                std::vector<int> v(len);
                for (int64_t row = begin; row < end; ++row) {
                    const int a = int(row % n), b = int(row / n);
                    auto index = [&](int i) -> size_t {
                        const Coord c = axis == 0   ? Coord(i, a, b)
                                        : axis == 1 ? Coord(a, i, b)
                                                    : Coord(a, b, i);
                        return spec.linearIndex(c);
                    };
                    f[0] = f[size_t(m) - 1] = 0.0;
                    for (int i = 0; i < n; ++i)
                        f[size_t(i) + 1] =
                            axis == 0 ? (inside[index(i)] ? BIG : 0.0) : double(d2[index(i)]);
                    edt1d(f, d, v, z);
                    for (int i = 0; i < n; ++i)
                        d2[index(i)] = float(d[size_t(i) + 1]);
                }
            },
            /*grain=*/16);
    };
    pass(0);
    pass(1);
    pass(2);
    std::vector<float> out(spec.voxelCount(), 0.f);
    for (size_t i = 0; i < out.size(); ++i)
        if (inside[i])
            out[i] = (std::sqrt(d2[i]) - 0.5f) * spec.voxelSize;
    return out;
}

void fillProcedural(MaterialVolume& volume, const ProceduralFill& fill, History* history) {
    LUCENT_CHECK(volume.brickCount() > 0, "fillProcedural: the material volume is empty");
    validateFill(fill);
    const PerlinNoise noise(fill.seed);
    const GridSpec& spec = volume.spec();
    const int n = spec.resolution;
    std::vector<float> depth;
    if (fill.pattern == ProceduralPattern::Layered)
        depth = distanceToSurface(volume);
    const Vector3f dir = glm::normalize(fill.direction);
    const float invScale = 1.f / fill.scale;

    int sel[MaterialVolume::COMPONENTS];
    const int nsel = selectedComponents(fill.channels, sel);

    std::vector<int> bricks;
    for (int b = 0; b < volume.brickCount(); ++b)
        if (volume.brickHasInside(b)) {
            if (history)
                history->recordBrick(volume, b);
            volume.markBrickDirty(b);
            bricks.push_back(b);
        }

    parallelFor(0, int64_t(bricks.size()), [&](int64_t begin, int64_t end) {
        for (int64_t bi = begin; bi < end; ++bi) {
            const int b = bricks[size_t(bi)];
            const Coord o = volume.brickOrigin(b);
            float* data = volume.brickData(b);
            for (int z = 0; z < MaterialVolume::BRICK && o.z + z < n; ++z)
                for (int y = 0; y < MaterialVolume::BRICK && o.y + y < n; ++y)
                    for (int x = 0; x < MaterialVolume::BRICK && o.x + x < n; ++x) {
                        const Coord c = o + Coord(x, y, z);
                        if (!volume.isInside(c))
                            continue;
                        const Point3f p = spec.cellCenter(c);
                        const Point3f q = p * invScale;
                        const int v = MaterialVolume::voxelInBrick(x, y, z);
                        if (fill.pattern == ProceduralPattern::Layered) {
                            float dd = depth[spec.linearIndex(c)];
                            if (fill.amplitude > 0.f)
                                dd += fill.amplitude * noise(q.x, q.y, q.z);
                            size_t layer = 0;
                            float top = 0.f;
                            while (layer + 1 < fill.layers.size() &&
                                   dd >= top + fill.layers[layer].thickness) {
                                top += fill.layers[layer].thickness;
                                ++layer;
                            }
                            for (int i = 0; i < nsel; ++i)
                                data[sel[i] * MaterialVolume::BRICK_VOXELS + v] =
                                    sampleComponent(fill.layers[layer].material, sel[i]);
                        } else {
                            float f;
                            if (fill.pattern == ProceduralPattern::Turbulence) {
                                f = noise.turbulence(q, fill.octaves);
                            } else {
                                // Perlin 1985, Sec. 5 marble: sin(x + turbulence(x)), here with
                                // stripes of period `scale` along `direction`, mapped to [0, 1].
                                const float phase =
                                    2.f * PI * glm::dot(q, dir) +
                                    fill.amplitude * noise.turbulence(q, fill.octaves);
                                f = std::pow(0.5f * (1.f + std::sin(phase)), fill.sharpness);
                            }
                            for (int i = 0; i < nsel; ++i) {
                                const float a = sampleComponent(fill.materialA, sel[i]);
                                const float bb = sampleComponent(fill.materialB, sel[i]);
                                data[sel[i] * MaterialVolume::BRICK_VOXELS + v] = a + f * (bb - a);
                            }
                        }
                        sanitizeVoxel(data, v);
                    }
        }
    });
}

}  // namespace lucent
