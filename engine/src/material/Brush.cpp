// SPDX-License-Identifier: MIT
/// @file
/// @brief Brush stamps, strokes and interior fills (Brush.h).
#include <lucent/material/Brush.h>

#include <lucent/core/Error.h>
#include <lucent/material/History.h>

#include "BrushOps.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace lucent {

using detail::sampleComponent;
using detail::sanitizeVoxel;
using detail::selectedComponents;

BrushSettings startingBrush() {
    BrushSettings b;
    b.radius = 3.f;
    b.falloff = Falloff::Smooth;
    b.strength = 0.5f;
    b.mode = BrushMode::Set;
    b.channels = ALL_CHANNELS;
    b.value = {Rgb(1.f), Rgb(0.8f), Rgb(0.f)};
    return b;
}

namespace {

constexpr int BRICK = MaterialVolume::BRICK;
constexpr int BV = MaterialVolume::BRICK_VOXELS;

const char* modeName(BrushMode m) {
    switch (m) {
        case BrushMode::Set:
            return "Set";
        case BrushMode::Add:
            return "Add";
        case BrushMode::Subtract:
            return "Subtract";
        case BrushMode::Multiply:
            return "Multiply";
        case BrushMode::Smooth:
            return "Smooth";
        case BrushMode::ResetToBase:
            return "ResetToBase";
    }
    return "?";
}

const char* componentName(int k) {
    static const char* names[] = {"sigma_t.r", "sigma_t.g", "sigma_t.b", "sigma_s.r", "sigma_s.g",
                                  "sigma_s.b", "g.r",       "g.g",       "g.b"};
    return names[k];
}

void checkVolumeReady(const MaterialVolume& volume, const char* what) {
    LUCENT_CHECK(volume.brickCount() > 0 && !volume.insideMask().empty(), what,
                 ": the material volume is empty (default-constructed)");
}

}  // namespace

float falloffWeight(Falloff falloff, float t) {
    if (!(t < 1.f))
        return 0.f;
    t = std::max(t, 0.f);
    switch (falloff) {
        case Falloff::Constant:
            return 1.f;
        case Falloff::Linear:
            return 1.f - t;
        // Hermite smoothstep 3t² − 2t³ (Ebert et al., "Texturing & Modeling", 3rd ed., 2003,
        // Sec. 2.1), mirrored so the weight falls from 1 at the centre to 0 at the rim.
        case Falloff::Smooth:
            return 1.f - t * t * (3.f - 2.f * t);
        // Gaussian exp(−t²/(2σ²)) with σ = 1/3 of the radius: the rim is at 3σ.
        case Falloff::Gaussian:
            return std::exp(-4.5f * t * t);
    }
    return 0.f;
}

void validateBrush(const BrushSettings& b) {
    LUCENT_CHECK(std::isfinite(b.radius) && b.radius > 0.f && b.radius <= BrushSettings::MAX_RADIUS,
                 "brush.radius = ", b.radius, " mm must be finite and in (0, ",
                 BrushSettings::MAX_RADIUS, "]");
    LUCENT_CHECK(std::isfinite(b.strength) && b.strength >= 0.f && b.strength <= 1.f,
                 "brush.strength = ", b.strength, " must be in [0, 1]");
    LUCENT_CHECK(std::isfinite(b.spacing) && b.spacing >= BrushSettings::MIN_SPACING &&
                     b.spacing <= BrushSettings::MAX_SPACING,
                 "brush.spacing = ", b.spacing, " (× radius) must be in [",
                 BrushSettings::MIN_SPACING, ", ", BrushSettings::MAX_SPACING, "]");
    LUCENT_CHECK(uint8_t(b.falloff) <= uint8_t(Falloff::Gaussian),
                 "brush.falloff = ", int(b.falloff), " is not a Falloff");
    LUCENT_CHECK(uint8_t(b.mode) <= uint8_t(BrushMode::ResetToBase), "brush.mode = ", int(b.mode),
                 " is not a BrushMode");
    LUCENT_CHECK(b.channels != 0 && (b.channels & ~ALL_CHANNELS) == 0,
                 "brush.channels = ", int(b.channels),
                 " must be a nonzero combination of SigmaT=1, SigmaS=2, G=4");
    for (int k = 0; k < MaterialVolume::COMPONENTS; ++k)
        LUCENT_CHECK(std::isfinite(sampleComponent(b.value, k)), "brush.value.", componentName(k),
                     " is NaN or infinite");
    int sel[MaterialVolume::COMPONENTS];
    const int nsel = selectedComponents(b.channels, sel);
    for (int i = 0; i < nsel; ++i) {
        const int k = sel[i];
        const float u = sampleComponent(b.value, k);
        const bool isG = k >= 6;
        switch (b.mode) {
            case BrushMode::Set:
                if (isG)
                    LUCENT_CHECK(std::abs(u) <= G_MAX, "brush.value.", componentName(k), " = ", u,
                                 " must be in [-", G_MAX, ", ", G_MAX, "] for mode Set");
                else
                    LUCENT_CHECK(u >= 0.f && u <= SIGMA_MAX, "brush.value.", componentName(k),
                                 " = ", u, " mm^-1 must be in [0, ", SIGMA_MAX, "] for mode Set");
                break;
            case BrushMode::Add:
            case BrushMode::Subtract:
                LUCENT_CHECK(u >= 0.f && u <= (isG ? 2.f * G_MAX : SIGMA_MAX), "brush.value.",
                             componentName(k), " = ", u, " must be a non-negative amount (max ",
                             isG ? 2.f * G_MAX : SIGMA_MAX, ") for mode ", modeName(b.mode));
                break;
            case BrushMode::Multiply:
                LUCENT_CHECK(u >= 0.f && u <= BrushSettings::MAX_FACTOR, "brush.value.",
                             componentName(k), " = ", u, " must be a factor in [0, ",
                             BrushSettings::MAX_FACTOR, "] for mode Multiply");
                break;
            case BrushMode::Smooth:
            case BrushMode::ResetToBase:
                break;
        }
    }
    if (b.mode == BrushMode::Set && (b.channels & uint8_t(Channel::SigmaT)) &&
        (b.channels & uint8_t(Channel::SigmaS))) {
        for (int c = 0; c < 3; ++c)
            LUCENT_CHECK(b.value.sigma_s[c] <= b.value.sigma_t[c], "brush.value.sigma_s[", c,
                         "] = ", b.value.sigma_s[c], " exceeds brush.value.sigma_t[", c,
                         "] = ", b.value.sigma_t[c], " (σs′ ≤ σt is required)");
    }
}

size_t stamp(MaterialVolume& volume, const BrushSettings& brush, const Point3f& center,
             History* history) {
    validateBrush(brush);
    checkVolumeReady(volume, "stamp");
    LUCENT_CHECK(isFinite(center), "stamp: centre (", center.x, ", ", center.y, ", ", center.z,
                 ") is not finite");
    if (brush.strength == 0.f)
        return 0;

    const GridSpec& spec = volume.spec();
    const int n = spec.resolution;
    const double h = spec.voxelSize;
    const double r = brush.radius;
    const double r2 = r * r;
    const double invR = 1.0 / r;
    // Voxel centres origin + (i + ½)h within r of the centre lie in this index box.
    Coord lo, hi;
    for (int a = 0; a < 3; ++a) {
        const double rel = (double(center[a]) - double(spec.origin[a])) / h - 0.5;
        const double l = std::floor(rel - r / h), u = std::ceil(rel + r / h);
        lo[a] = int(std::clamp(l, -1.0, double(n)));
        hi[a] = int(std::clamp(u, -1.0, double(n)));
        lo[a] = std::max(lo[a], 0);
        hi[a] = std::min(hi[a], n - 1);
        if (lo[a] > hi[a])
            return 0;
    }

    int sel[MaterialVolume::COMPONENTS];
    const int nsel = selectedComponents(brush.channels, sel);
    float target[MaterialVolume::COMPONENTS];
    for (int k = 0; k < MaterialVolume::COMPONENTS; ++k)
        target[k] = brush.mode == BrushMode::ResetToBase ? sampleComponent(volume.base(), k)
                                                         : sampleComponent(brush.value, k);

    // Smooth reads the pre-stamp values of the box grown by one voxel (order-independent):
    // 3×3×3 box sums of the inside values and of the inside count, computed separably.
    std::vector<double> boxSum, boxCount;
    Coord slo(0), sdim(0);
    if (brush.mode == BrushMode::Smooth) {
        slo = glm::max(lo - 1, Coord(0));
        const Coord shi = glm::min(hi + 1, Coord(n - 1));
        sdim = shi - slo + 1;
        const size_t cnt = size_t(sdim.x) * sdim.y * sdim.z;
        boxSum.assign(cnt * size_t(nsel), 0.0);
        boxCount.assign(cnt, 0.0);
        const std::vector<uint8_t>& inMask = volume.insideMask();
        for (int z = 0; z < sdim.z; ++z)
            for (int y = 0; y < sdim.y; ++y) {
                const int gz = slo.z + z, gy = slo.y + y;
                const size_t maskRow = (size_t(gz) * n + gy) * n;
                for (int x = 0; x < sdim.x; ++x) {
                    const int gx = slo.x + x;
                    if (!inMask[maskRow + size_t(gx)])
                        continue;
                    const float* brick = volume.brickData(volume.brickIndexOf({gx, gy, gz}));
                    const int v = MaterialVolume::voxelInBrick(gx % BRICK, gy % BRICK, gz % BRICK);
                    const size_t li = (size_t(z) * sdim.y + y) * sdim.x + x;
                    boxCount[li] = 1.0;
                    for (int i = 0; i < nsel; ++i)
                        boxSum[size_t(i) * cnt + li] = brick[sel[i] * BV + v];
                }
            }
        std::vector<double> line;
        auto box3 = [&](double* a) {
            const size_t stride[3] = {1, size_t(sdim.x), size_t(sdim.x) * sdim.y};
            for (int axis = 0; axis < 3; ++axis) {
                const int len = sdim[axis];
                line.resize(size_t(len));
                const int u = axis == 0 ? 1 : 0, w = axis == 2 ? 1 : 2;
                for (int j = 0; j < sdim[w]; ++j)
                    for (int i = 0; i < sdim[u]; ++i) {
                        double* base = a + size_t(i) * stride[u] + size_t(j) * stride[w];
                        for (int k = 0; k < len; ++k)
                            line[size_t(k)] = base[size_t(k) * stride[axis]];
                        for (int k = 0; k < len; ++k)
                            base[size_t(k) * stride[axis]] =
                                line[size_t(k)] + (k > 0 ? line[size_t(k) - 1] : 0.0) +
                                (k + 1 < len ? line[size_t(k) + 1] : 0.0);
                    }
            }
        };
        box3(boxCount.data());
        for (int i = 0; i < nsel; ++i)
            box3(boxSum.data() + size_t(i) * cnt);
    }
    const size_t snapCount = size_t(sdim.x) * sdim.y * sdim.z;

    // Per-voxel update with the mode fixed at compile time (keeps the switch out of the loop).
    auto run = [&](auto modeTag) -> size_t {
        constexpr BrushMode MODE = decltype(modeTag)::value;
        const std::vector<uint8_t>& mask = volume.insideMask();
        size_t touched = 0;
        const float strength = brush.strength;
        const Coord blo = lo / BRICK, bhi = hi / BRICK;
        for (int bz = blo.z; bz <= bhi.z; ++bz)
            for (int by = blo.y; by <= bhi.y; ++by)
                for (int bx = blo.x; bx <= bhi.x; ++bx) {
                    const int b = (bz * volume.bricksPerAxis() + by) * volume.bricksPerAxis() + bx;
                    if (!volume.brickHasInside(b))
                        continue;
                    const Coord o(bx * BRICK, by * BRICK, bz * BRICK);
                    const Coord vlo = glm::max(lo, o), vhi = glm::min(hi, o + (BRICK - 1));
                    float* data = nullptr;
                    for (int z = vlo.z; z <= vhi.z; ++z) {
                        const double dz = (double(spec.origin.z) + (z + 0.5) * h) - center.z;
                        for (int y = vlo.y; y <= vhi.y; ++y) {
                            const double dy = (double(spec.origin.y) + (y + 0.5) * h) - center.y;
                            const double dyz2 = dy * dy + dz * dz;
                            if (dyz2 >= r2)
                                continue;
                            // Weights of the row segment; 0 for voxels the stamp does not touch,
                            // which leaves them bit-identical below (v + 0·(…) = v, v·1 = v,
                            // and sanitising a valid voxel is the identity).
                            const size_t rowBase = (size_t(z) * n + y) * n;
                            float wrow[BRICK] = {};
                            int rowTouched = 0;
                            for (int x = vlo.x; x <= vhi.x; ++x) {
                                const double dx =
                                    (double(spec.origin.x) + (x + 0.5) * h) - center.x;
                                const double d2 = dx * dx + dyz2;
                                if (d2 >= r2 || !mask[rowBase + size_t(x)])
                                    continue;
                                wrow[x - o.x] =
                                    strength *
                                    falloffWeight(brush.falloff, float(std::sqrt(d2) * invR));
                                ++rowTouched;
                            }
                            if (rowTouched == 0)
                                continue;
                            if (!data) {
                                if (history)
                                    history->recordBrick(volume, b);
                                volume.markBrickDirty(b);
                                data = volume.brickData(b);
                            }
                            touched += size_t(rowTouched);
                            const int v0 = MaterialVolume::voxelInBrick(0, y - o.y, z - o.z);
                            const int xa = vlo.x - o.x, xb = vhi.x - o.x;
                            for (int i = 0; i < nsel; ++i) {
                                float* row = data + sel[i] * BV + v0;
                                const float u = target[sel[i]];
                                if constexpr (MODE == BrushMode::Smooth) {
                                    // Mean of the inside voxels of the 3×3×3 box; the count is
                                    // ≥ 1 wherever w > 0 because the voxel itself is inside.
                                    const size_t li0 =
                                        (size_t(z - slo.z) * sdim.y + size_t(y - slo.y)) * sdim.x +
                                        size_t(o.x - slo.x);
                                    const double* sum = boxSum.data() + size_t(i) * snapCount;
                                    for (int x = xa; x <= xb; ++x) {
                                        if (wrow[x] == 0.f)
                                            continue;
                                        const float m =
                                            float(sum[li0 + size_t(x)] / boxCount[li0 + size_t(x)]);
                                        row[x] += wrow[x] * (m - row[x]);
                                    }
                                } else {
                                    for (int x = xa; x <= xb; ++x) {
                                        const float w = wrow[x];
                                        if constexpr (MODE == BrushMode::Set ||
                                                      MODE == BrushMode::ResetToBase)
                                            row[x] += w * (u - row[x]);
                                        else if constexpr (MODE == BrushMode::Add)
                                            row[x] += w * u;
                                        else if constexpr (MODE == BrushMode::Subtract)
                                            row[x] -= w * u;
                                        else
                                            row[x] *= 1.f + w * (u - 1.f);
                                    }
                                }
                            }
                            for (int x = xa; x <= xb; ++x)
                                sanitizeVoxel(data, v0 + x);
                        }
                    }
                }
        return touched;
    };
    switch (brush.mode) {
        case BrushMode::Set:
            return run(std::integral_constant<BrushMode, BrushMode::Set>{});
        case BrushMode::Add:
            return run(std::integral_constant<BrushMode, BrushMode::Add>{});
        case BrushMode::Subtract:
            return run(std::integral_constant<BrushMode, BrushMode::Subtract>{});
        case BrushMode::Multiply:
            return run(std::integral_constant<BrushMode, BrushMode::Multiply>{});
        case BrushMode::Smooth:
            return run(std::integral_constant<BrushMode, BrushMode::Smooth>{});
        case BrushMode::ResetToBase:
            return run(std::integral_constant<BrushMode, BrushMode::ResetToBase>{});
    }
    return 0;  // unreachable: validateBrush() rejected unknown modes
}

std::vector<Point3f> strokeStamps(const std::vector<Point3f>& path, const BrushSettings& brush) {
    validateBrush(brush);
    LUCENT_CHECK(!path.empty(), "stroke path is empty");
    for (size_t i = 0; i < path.size(); ++i)
        LUCENT_CHECK(isFinite(path[i]), "stroke path point ", i, " is not finite");
    const double s = double(brush.spacing) * brush.radius;
    double length = 0.0;
    for (size_t i = 1; i < path.size(); ++i)
        length += glm::length(glm::dvec3(path[i] - path[i - 1]));
    const double count = std::floor(length / s) + 1.0;
    LUCENT_CHECK(count <= double(BrushSettings::MAX_STAMPS_PER_STROKE), "stroke of ", length,
                 " mm at spacing ", s, " mm needs ", count, " stamps (max ",
                 BrushSettings::MAX_STAMPS_PER_STROKE, ")");
    std::vector<Point3f> out;
    out.reserve(size_t(count));
    out.push_back(path.front());
    double next = s;  // arc length of the next stamp
    double travelled = 0.0;
    for (size_t i = 1; i < path.size(); ++i) {
        const glm::dvec3 a(path[i - 1]), d = glm::dvec3(path[i]) - a;
        const double len = glm::length(d);
        while (len > 0.0 && next <= travelled + len && out.size() < size_t(count)) {
            out.push_back(Point3f(a + d * ((next - travelled) / len)));
            next += s;
        }
        travelled += len;
    }
    return out;
}

size_t paintStroke(MaterialVolume& volume, const BrushSettings& brush,
                   const std::vector<Point3f>& path, History* history) {
    size_t total = 0;
    for (const Point3f& p : strokeStamps(path, brush))
        total += stamp(volume, brush, p, history);
    return total;
}

void fillInterior(MaterialVolume& volume, const MaterialSample& value, ChannelMask channels,
                  History* history) {
    checkVolumeReady(volume, "fillInterior");
    LUCENT_CHECK(channels != 0 && (channels & ~ALL_CHANNELS) == 0,
                 "fillInterior: channels = ", int(channels),
                 " must be a nonzero combination of SigmaT=1, SigmaS=2, G=4");
    for (int k = 0; k < MaterialVolume::COMPONENTS; ++k) {
        const float u = sampleComponent(value, k);
        LUCENT_CHECK(std::isfinite(u), "fillInterior: value.", componentName(k),
                     " is NaN or infinite");
        if (k < 6)
            LUCENT_CHECK(u >= 0.f && u <= SIGMA_MAX, "fillInterior: value.", componentName(k),
                         " = ", u, " mm^-1 must be in [0, ", SIGMA_MAX, "]");
        else
            LUCENT_CHECK(std::abs(u) <= G_MAX, "fillInterior: value.", componentName(k), " = ", u,
                         " must be in [-", G_MAX, ", ", G_MAX, "]");
    }
    int sel[MaterialVolume::COMPONENTS];
    const int nsel = selectedComponents(channels, sel);
    const int n = volume.resolution();
    for (int b = 0; b < volume.brickCount(); ++b) {
        if (!volume.brickHasInside(b))
            continue;
        if (history)
            history->recordBrick(volume, b);
        volume.markBrickDirty(b);
        const Coord o = volume.brickOrigin(b);
        float* data = volume.brickData(b);
        for (int z = 0; z < BRICK && o.z + z < n; ++z)
            for (int y = 0; y < BRICK && o.y + y < n; ++y)
                for (int x = 0; x < BRICK && o.x + x < n; ++x) {
                    if (!volume.isInside(o + Coord(x, y, z)))
                        continue;
                    const int v = MaterialVolume::voxelInBrick(x, y, z);
                    for (int i = 0; i < nsel; ++i)
                        data[sel[i] * BV + v] = sampleComponent(value, sel[i]);
                    sanitizeVoxel(data, v);
                }
    }
}

}  // namespace lucent
