// SPDX-License-Identifier: MIT
/// @file
/// @brief MaterialVolume brick storage, GridSpec::around and sanitize() (Medium.h).
#include <lucent/material/MaterialVolume.h>

#include <lucent/core/Error.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace lucent {

namespace {

float clampFinite(float v, float lo, float hi) {
    if (std::isnan(v))
        return 0.f;  // NaN → 0 (Medium.h contract); ±Inf clamps to the bounds
    return std::clamp(v, lo, hi);
}

void checkSpec(const GridSpec& spec) {
    LUCENT_CHECK(spec.resolution >= 1 && spec.resolution <= GridSpec::MAX_RESOLUTION,
                 "GridSpec.resolution = ", spec.resolution, " is outside [1, ",
                 GridSpec::MAX_RESOLUTION, "]");
    LUCENT_CHECK(std::isfinite(spec.voxelSize) && spec.voxelSize > 0.f,
                 "GridSpec.voxelSize = ", spec.voxelSize, " mm must be finite and > 0");
    LUCENT_CHECK(isFinite(spec.origin), "GridSpec.origin must be finite");
}

}  // namespace

MaterialSample sanitize(const MaterialSample& s) {
    MaterialSample out;
    for (int c = 0; c < 3; ++c) {
        out.sigma_t[c] = clampFinite(s.sigma_t[c], 0.f, SIGMA_MAX);
        out.sigma_s[c] = clampFinite(s.sigma_s[c], 0.f, out.sigma_t[c]);
        out.g[c] = clampFinite(s.g[c], -G_MAX, G_MAX);
    }
    return out;
}

GridSpec GridSpec::around(const Bounds3f& bounds, int resolution, float padVoxels) {
    LUCENT_CHECK(!bounds.isEmpty() && isFinite(bounds.lo) && isFinite(bounds.hi),
                 "GridSpec::around: bounds are empty or not finite");
    LUCENT_CHECK(resolution >= MIN_RESOLUTION && resolution <= MAX_RESOLUTION,
                 "GridSpec::around: resolution = ", resolution, " is outside [", MIN_RESOLUTION,
                 ", ", MAX_RESOLUTION, "]");
    LUCENT_CHECK(std::isfinite(padVoxels) && padVoxels >= 0.f && 2.f * padVoxels < resolution,
                 "GridSpec::around: padVoxels = ", padVoxels, " must be in [0, resolution/2)");
    const Vector3f ext = bounds.extent();
    float longest = std::max({ext.x, ext.y, ext.z});
    if (longest <= 0.f)
        longest = 1.f;  // a single point: a 1 mm box around it
    // resolution·h = longest + 2·pad·h  ⇒  h = longest / (resolution − 2·pad).
    GridSpec spec;
    spec.resolution = resolution;
    spec.voxelSize = longest / (float(resolution) - 2.f * padVoxels);
    spec.origin = bounds.center() - Vector3f(0.5f * spec.voxelSize * float(resolution));
    return spec;
}

MaterialVolume::MaterialVolume(const GridSpec& spec, const MaterialSample& base)
    : m_spec(spec), m_base(sanitize(base)) {
    checkSpec(spec);
    m_bricksPerAxis = (spec.resolution + BRICK - 1) / BRICK;
    m_data.assign(size_t(brickCount()) * BRICK_VOXELS * COMPONENTS, 0.f);
    m_inside.assign(spec.voxelCount(), 1);
    m_brickInside.assign(size_t(brickCount()), 1);
    m_dirty.assign(size_t(brickCount()), 0);
    // Fill every in-grid voxel with the base value (voxels of partial bricks beyond the grid
    // stay 0 and are never read).
    const int n = spec.resolution;
    for (int b = 0; b < brickCount(); ++b) {
        const Coord o = brickOrigin(b);
        float* data = brickData(b);
        for (int z = 0; z < BRICK && o.z + z < n; ++z)
            for (int y = 0; y < BRICK && o.y + y < n; ++y)
                for (int x = 0; x < BRICK && o.x + x < n; ++x) {
                    const int v = voxelInBrick(x, y, z);
                    for (int c = 0; c < 3; ++c) {
                        data[(0 + c) * BRICK_VOXELS + v] = m_base.sigma_t[c];
                        data[(3 + c) * BRICK_VOXELS + v] = m_base.sigma_s[c];
                        data[(6 + c) * BRICK_VOXELS + v] = m_base.g[c];
                    }
                }
    }
    markAllDirty();
}

void MaterialVolume::setEta(float eta) {
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.f && eta <= 3.f,
                 "MaterialVolume::setEta: eta = ", eta, " is outside [1, 3]");
    m_eta = eta;
    ++m_revision;
}

void MaterialVolume::setBase(const MaterialSample& base) {
    m_base = sanitize(base);
    ++m_revision;
}

MaterialSample MaterialVolume::at(const Coord& c) const {
    LUCENT_ASSERT(m_spec.contains(c));
    MaterialSample s;
    if (!isInside(c))
        return s;
    const float* data = brickData(brickIndexOf(c));
    const int v = voxelInBrick(c.x % BRICK, c.y % BRICK, c.z % BRICK);
    for (int ch = 0; ch < 3; ++ch) {
        s.sigma_t[ch] = data[(0 + ch) * BRICK_VOXELS + v];
        s.sigma_s[ch] = data[(3 + ch) * BRICK_VOXELS + v];
        s.g[ch] = data[(6 + ch) * BRICK_VOXELS + v];
    }
    return s;
}

MaterialSample MaterialVolume::sample(const Point3f& p) const {
    if (m_data.empty() || !isFinite(p))
        return {};
    const Coord c = m_spec.cellOf(p);
    if (!m_spec.contains(c))
        return {};
    return at(c);
}

void MaterialVolume::set(const Coord& c, const MaterialSample& s) {
    LUCENT_CHECK(m_spec.contains(c), "MaterialVolume::set: voxel (", c.x, ", ", c.y, ", ", c.z,
                 ") is outside the ", m_spec.resolution, "³ grid");
    if (!isInside(c))
        return;
    const MaterialSample v = sanitize(s);
    const int b = brickIndexOf(c);
    float* data = brickData(b);
    const int i = voxelInBrick(c.x % BRICK, c.y % BRICK, c.z % BRICK);
    for (int ch = 0; ch < 3; ++ch) {
        data[(0 + ch) * BRICK_VOXELS + i] = v.sigma_t[ch];
        data[(3 + ch) * BRICK_VOXELS + i] = v.sigma_s[ch];
        data[(6 + ch) * BRICK_VOXELS + i] = v.g[ch];
    }
    markBrickDirty(b);
}

float MaterialVolume::component(const Coord& c, int comp) const {
    LUCENT_ASSERT(m_spec.contains(c) && comp >= 0 && comp < COMPONENTS);
    const float* data = brickData(brickIndexOf(c));
    return data[comp * BRICK_VOXELS + voxelInBrick(c.x % BRICK, c.y % BRICK, c.z % BRICK)];
}

uint64_t MaterialVolume::contentHash() const {
    uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a 64 offset basis and prime
    const auto feed = [&h](const void* data, size_t n) {
        const auto* p = static_cast<const unsigned char*>(data);
        for (size_t i = 0; i < n; ++i)
            h = (h ^ p[i]) * 0x100000001b3ull;
    };
    feed(m_inside.data(), m_inside.size());
    feed(m_data.data(), m_data.size() * sizeof(float));
    return h;
}

void MaterialVolume::setInsideMask(const std::vector<uint8_t>& inside) {
    LUCENT_CHECK(inside.size() == m_spec.voxelCount(), "MaterialVolume::setInsideMask: mask has ",
                 inside.size(), " entries, the grid has ", m_spec.voxelCount(), " voxels");
    const int n = m_spec.resolution;
    std::fill(m_brickInside.begin(), m_brickInside.end(), uint8_t(0));
    for (int b = 0; b < brickCount(); ++b) {
        const Coord o = brickOrigin(b);
        float* data = brickData(b);
        for (int z = 0; z < BRICK && o.z + z < n; ++z)
            for (int y = 0; y < BRICK && o.y + y < n; ++y)
                for (int x = 0; x < BRICK && o.x + x < n; ++x) {
                    const Coord c = o + Coord(x, y, z);
                    const size_t li = m_spec.linearIndex(c);
                    const bool now = inside[li] != 0;
                    const bool before = m_inside[li] != 0;
                    const int v = voxelInBrick(x, y, z);
                    if (now && !before) {
                        for (int ch = 0; ch < 3; ++ch) {
                            data[(0 + ch) * BRICK_VOXELS + v] = m_base.sigma_t[ch];
                            data[(3 + ch) * BRICK_VOXELS + v] = m_base.sigma_s[ch];
                            data[(6 + ch) * BRICK_VOXELS + v] = m_base.g[ch];
                        }
                    } else if (!now) {
                        for (int k = 0; k < COMPONENTS; ++k)
                            data[k * BRICK_VOXELS + v] = 0.f;
                    }
                    m_inside[li] = now ? 1 : 0;
                    if (now)
                        m_brickInside[b] = 1;
                }
    }
    markAllDirty();
}

Coord MaterialVolume::brickOrigin(int b) const {
    LUCENT_ASSERT(b >= 0 && b < brickCount());
    const int n = m_bricksPerAxis;
    return Coord(b % n, (b / n) % n, b / (n * n)) * BRICK;
}

int MaterialVolume::brickIndexOf(const Coord& c) const {
    LUCENT_ASSERT(m_spec.contains(c));
    const int n = m_bricksPerAxis;
    return ((c.z / BRICK) * n + c.y / BRICK) * n + c.x / BRICK;
}

void MaterialVolume::markAllDirty() {
    std::fill(m_dirty.begin(), m_dirty.end(), uint8_t(1));
    ++m_revision;
}

std::vector<int> MaterialVolume::takeDirtyBricks() {
    std::vector<int> out;
    for (int b = 0; b < brickCount(); ++b)
        if (m_dirty[b]) {
            out.push_back(b);
            m_dirty[b] = 0;
        }
    return out;
}

std::vector<float> MaterialVolume::denseComponent(int comp) const {
    LUCENT_CHECK(comp >= 0 && comp < COMPONENTS, "MaterialVolume::denseComponent: component ", comp,
                 " is outside [0, ", COMPONENTS, ")");
    const int n = m_spec.resolution;
    std::vector<float> out(m_spec.voxelCount(), 0.f);
    for (int b = 0; b < brickCount(); ++b) {
        const Coord o = brickOrigin(b);
        const float* src = brickData(b) + size_t(comp) * BRICK_VOXELS;
        for (int z = 0; z < BRICK && o.z + z < n; ++z)
            for (int y = 0; y < BRICK && o.y + y < n; ++y) {
                const int xs = std::min(BRICK, n - o.x);
                std::memcpy(&out[m_spec.linearIndex(o + Coord(0, y, z))],
                            src + voxelInBrick(0, y, z), sizeof(float) * size_t(xs));
            }
    }
    return out;
}

bool MaterialVolume::isHomogeneous() const {
    const int n = m_spec.resolution;
    bool haveRef = false;
    float ref[COMPONENTS] = {};
    for (int b = 0; b < brickCount(); ++b) {
        if (!m_brickInside[b])
            continue;
        const Coord o = brickOrigin(b);
        const float* data = brickData(b);
        for (int z = 0; z < BRICK && o.z + z < n; ++z)
            for (int y = 0; y < BRICK && o.y + y < n; ++y)
                for (int x = 0; x < BRICK && o.x + x < n; ++x) {
                    if (!isInside(o + Coord(x, y, z)))
                        continue;
                    const int v = voxelInBrick(x, y, z);
                    if (!haveRef) {
                        for (int k = 0; k < COMPONENTS; ++k)
                            ref[k] = data[k * BRICK_VOXELS + v];
                        haveRef = true;
                        continue;
                    }
                    for (int k = 0; k < COMPONENTS; ++k)
                        if (data[k * BRICK_VOXELS + v] != ref[k])
                            return false;
                }
    }
    return true;
}

}  // namespace lucent
