// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The path tracer's view of a painted material: unreduced coefficients per voxel
/// (σt, σs, g per RGB channel, mm⁻¹) on the MaterialVolume's cell-centred grid, with a
/// per-brick majorant grid for null-collision tracking.
///
///     GridMedium medium = GridMedium::fromMaterial(volume);      // toMedium() per voxel
///     medium.forEachMajorantSegment(o, d, 0.f, tMax, ch, [&](float t0, float t1, float m) {
///         ...; return true;                                       // false stops the walk
///     });
///
/// Lookups are nearest / piecewise constant (the rule of MaterialVolume.h); σ is zero outside
/// the grid. The majorant of a brick is the largest σt of its voxels, which bounds σt exactly
/// on the brick's box because voxel and brick boundaries coincide.

#include <lucent/core/Types.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/material/Medium.h>

#include <array>
#include <cstdint>
#include <vector>

namespace lucent::reference {

/// How the free-flight sampler bounds σt.
enum class MajorantMode : uint8_t {
    Bricks,  ///< one majorant per brick of BRICK³ voxels, traversed by DDA (empty bricks skipped)
    Global,  ///< one majorant for the whole grid (the baseline the bricks are measured against)
    /// Bricks when the global majorant is on average ≥ 4× the majorant of the non-empty
    /// bricks (sparse or strongly varying media), else Global (dense, nearly uniform objects,
    /// where the DDA costs more than the null collisions it saves).
    Auto,
};

/// Unreduced per-voxel coefficients with a majorant grid. Immutable after construction, so it
/// is safe to share between threads.
class GridMedium {
public:
    static constexpr int BRICK = MaterialVolume::BRICK;  ///< majorant brick edge, voxels
    /// Pseudo-channel for majorant queries: the largest majorant of the three channels (the
    /// common majorant of spectral MIS tracking).
    static constexpr int ANY_CHANNEL = 3;

    struct Options {
        MajorantMode majorant = MajorantMode::Bricks;
        /// When every voxel holds the same value, sample free flights and transmittance in
        /// closed form (exponential) instead of by null collisions.
        bool homogeneousFastPath = true;
    };

    GridMedium() = default;
    /// @param spec grid placement (mm).
    /// @param voxels spec.voxelCount() unreduced coefficients, x fastest (σa is ignored; σt,
    ///        σs and g are used as given).
    /// @throw ValueError if the count is wrong or a coefficient is negative / non-finite /
    ///        σs > σt (beyond rounding) / |g| ≥ 1.
    GridMedium(const GridSpec& spec, const std::vector<MediumCoefficients>& voxels,
               const Options& options);
    /// The painted volume through the shared mapping toMedium() (Medium.h). Masked-out voxels
    /// next to the inside carry the material of their inside neighbours (boundarySkin,
    /// BoundarySkin.h), since the mesh that bounds the medium partly fills them; the others
    /// are empty.
    static GridMedium fromMaterial(const MaterialVolume& volume, const Options& options);
    /// One value everywhere inside `spec`'s box.
    static GridMedium uniform(const GridSpec& spec, const MediumCoefficients& value,
                              const Options& options);

    [[nodiscard]] const GridSpec& spec() const { return m_spec; }
    [[nodiscard]] const Options& options() const { return m_options; }
    /// The majorant mode in effect (Auto resolved to Bricks or Global).
    [[nodiscard]] MajorantMode majorantMode() const {
        return m_cells > 1 ? MajorantMode::Bricks : MajorantMode::Global;
    }
    /// True when the homogeneous fast path is enabled and every voxel holds the same value.
    [[nodiscard]] bool isHomogeneous() const { return m_homogeneous; }

    //! @{ \name Point lookups (nearest voxel; zero outside the grid)
    [[nodiscard]] float sigmaT(const Point3f& p, int ch) const {
        const int64_t i = voxelIndex(p);
        return i < 0 ? 0.f : m_sigmaT[ch][size_t(i)];
    }
    [[nodiscard]] float sigmaS(const Point3f& p, int ch) const {
        const int64_t i = voxelIndex(p);
        return i < 0 ? 0.f : m_sigmaS[ch][size_t(i)];
    }
    [[nodiscard]] float g(const Point3f& p, int ch) const {
        const int64_t i = voxelIndex(p);
        return i < 0 ? 0.f : m_g[ch][size_t(i)];
    }
    /// Coefficients by linear voxel index (from voxelIndex(), ≥ 0).
    [[nodiscard]] float sigmaTAt(int64_t v, int ch) const { return m_sigmaT[ch][size_t(v)]; }
    [[nodiscard]] float sigmaSAt(int64_t v, int ch) const { return m_sigmaS[ch][size_t(v)]; }
    /// Linear voxel index of p, or −1 outside the grid.
    [[nodiscard]] int64_t voxelIndex(const Point3f& p) const {
        const Vector3f q = (p - m_spec.origin) * m_invVoxelSize;
        if (!(q.x >= 0.f && q.y >= 0.f && q.z >= 0.f))
            return -1;  // also rejects NaN
        const int x = int(q.x), y = int(q.y), z = int(q.z);
        const int r = m_spec.resolution;
        if (x >= r || y >= r || z >= r)
            return -1;
        return (int64_t(z) * r + y) * r + x;
    }
    //! @}

    //! @{ \name Majorants
    /// Largest σt of channel ch (0–2, or ANY_CHANNEL) over the whole grid (mm⁻¹).
    [[nodiscard]] float globalMajorant(int ch) const { return m_globalMajorant[size_t(ch)]; }
    /// Cells of the majorant grid per axis (1 in Global mode).
    [[nodiscard]] int majorantCells() const { return m_cells; }
    /// Calls `segment(t0, t1, majorant)` for consecutive pieces of the ray o + t·d,
    /// t ∈ [tMin, tMax] clipped to the grid box, each with a constant majorant of channel ch
    /// (0–2, or ANY_CHANNEL for the largest of the three).
    /// Stops when `segment` returns false. `d` need not be unit (t is in units of |d|).
    template <typename F>
    void forEachMajorantSegment(const Point3f& o, const Vector3f& d, float tMin, float tMax, int ch,
                                F&& segment) const;
    //! @}

private:
    void buildMajorants();
    void buildMajorants(MajorantMode mode);

    GridSpec m_spec;
    Options m_options;
    float m_invVoxelSize = 1.f;
    bool m_homogeneous = false;
    std::array<std::vector<float>, 3> m_sigmaT, m_sigmaS, m_g;  // per channel, x fastest
    std::array<float, 4> m_globalMajorant{0.f, 0.f, 0.f, 0.f};
    int m_cells = 0;                // majorant cells per axis
    float m_cellSize = 1.f;         // mm
    std::vector<float> m_majorant;  // cells³ × 4 (r, g, b, max; channel fastest)
};

template <typename F>
void GridMedium::forEachMajorantSegment(const Point3f& o, const Vector3f& d, float tMin, float tMax,
                                        int ch, F&& segment) const {
    if (m_cells == 0)
        return;
    // Clip to the grid box (slab test).
    const Bounds3f box = m_spec.bounds();
    float t0 = tMin, t1 = tMax;
    for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.f) {
            if (o[a] < box.lo[a] || o[a] > box.hi[a])
                return;
            continue;
        }
        const float inv = 1.f / d[a];
        float tn = (box.lo[a] - o[a]) * inv, tf = (box.hi[a] - o[a]) * inv;
        if (tn > tf)
            std::swap(tn, tf);
        t0 = std::max(t0, tn);
        t1 = std::min(t1, tf);
    }
    if (!(t0 < t1))
        return;
    if (m_cells == 1) {
        segment(t0, t1, m_majorant[size_t(ch)]);
        return;
    }
    // 3-D DDA over majorant cells (Amanatides & Woo 1987, "A fast voxel traversal algorithm").
    const Point3f pStart = o + d * t0;
    int cell[3], step[3];
    float tNext[3], tDelta[3];
    for (int a = 0; a < 3; ++a) {
        const float q = (pStart[a] - m_spec.origin[a]) / m_cellSize;
        cell[a] = std::clamp(int(std::floor(q)), 0, m_cells - 1);
        if (d[a] > 0.f) {
            step[a] = 1;
            tNext[a] = (m_spec.origin[a] + float(cell[a] + 1) * m_cellSize - o[a]) / d[a];
            tDelta[a] = m_cellSize / d[a];
        } else if (d[a] < 0.f) {
            step[a] = -1;
            tNext[a] = (m_spec.origin[a] + float(cell[a]) * m_cellSize - o[a]) / d[a];
            tDelta[a] = -m_cellSize / d[a];
        } else {
            step[a] = 0;
            tNext[a] = INF;
            tDelta[a] = INF;
        }
    }
    float t = t0;
    while (t < t1) {
        const int a =
            tNext[0] < tNext[1] ? (tNext[0] < tNext[2] ? 0 : 2) : (tNext[1] < tNext[2] ? 1 : 2);
        const float tEnd = std::min(tNext[a], t1);
        const size_t idx = (size_t(cell[2]) * m_cells + cell[1]) * m_cells + cell[0];
        if (tEnd > t && !segment(t, tEnd, m_majorant[idx * 4 + size_t(ch)]))
            return;
        t = std::max(t, tEnd);
        cell[a] += step[a];
        if (cell[a] < 0 || cell[a] >= m_cells)
            return;
        tNext[a] += tDelta[a];
    }
}

}  // namespace lucent::reference
