// SPDX-License-Identifier: MIT
/// @file
/// @brief GridMedium: validation, homogeneity detection and the per-brick majorant grid.

#include <lucent/core/Error.h>
#include <lucent/reference/GridMedium.h>

namespace lucent::reference {

GridMedium::GridMedium(const GridSpec& spec, const std::vector<MediumCoefficients>& voxels,
                       const Options& options)
    : m_spec(spec), m_options(options) {
    LUCENT_CHECK(spec.resolution >= 1 && spec.voxelSize > 0.f && std::isfinite(spec.voxelSize) &&
                     isFinite(spec.origin),
                 "GridMedium: invalid grid spec (resolution ", spec.resolution, ", voxelSize ",
                 spec.voxelSize, " mm)");
    LUCENT_CHECK(voxels.size() == spec.voxelCount(), "GridMedium: expected ", spec.voxelCount(),
                 " voxels, got ", voxels.size());
    m_invVoxelSize = 1.f / spec.voxelSize;
    for (int c = 0; c < 3; ++c) {
        m_sigmaT[c].resize(voxels.size());
        m_sigmaS[c].resize(voxels.size());
        m_g[c].resize(voxels.size());
    }
    bool same = true;
    for (size_t i = 0; i < voxels.size(); ++i) {
        const MediumCoefficients& v = voxels[i];
        for (int c = 0; c < 3; ++c) {
            const float st = v.sigma_t[c], ss = v.sigma_s[c], g = v.g[c];
            // σs may exceed σt by float rounding of σa + σs; anything more is an error.
            LUCENT_CHECK(std::isfinite(st) && std::isfinite(ss) && std::isfinite(g) && st >= 0.f &&
                             ss >= 0.f && ss <= st * (1.f + 1e-5f) + 1e-30f && std::abs(g) < 1.f,
                         "GridMedium: voxel ", i, " channel ", c, " has invalid coefficients (σt ",
                         st, ", σs ", ss, " mm⁻¹, g ", g, ")");
            m_sigmaT[c][i] = st;
            m_sigmaS[c][i] = std::min(ss, st);
            m_g[c][i] = g;
            if (i > 0 &&
                (st != m_sigmaT[c][0] || m_sigmaS[c][i] != m_sigmaS[c][0] || g != m_g[c][0]))
                same = false;
        }
    }
    m_homogeneous = same && options.homogeneousFastPath;
    buildMajorants();
}

GridMedium GridMedium::uniform(const GridSpec& spec, const MediumCoefficients& value,
                               const Options& options) {
    return GridMedium(spec, std::vector<MediumCoefficients>(spec.voxelCount(), value), options);
}

void GridMedium::buildMajorants() {
    if (m_options.majorant == MajorantMode::Auto) {
        // Cost model: inside a brick of majorant σ̄b a global majorant σ̄g makes σ̄g/σ̄b times
        // as many tentative collisions; the DDA costs about as much as a few of them per
        // free flight (measured, docs/benchmarks.md). Keep the bricks when the mean of σ̄g/σ̄b
        // over non-empty bricks is ≥ AUTO_BRICK_GAIN.
        constexpr double AUTO_BRICK_GAIN = 4.0;
        buildMajorants(MajorantMode::Bricks);
        const float global = m_globalMajorant[ANY_CHANNEL];
        double gain = 0.0;
        size_t nonEmpty = 0;
        for (size_t cell = 0; cell + 3 < m_majorant.size(); cell += 4) {
            const float m = m_majorant[cell + ANY_CHANNEL];
            if (m > 0.f) {
                gain += double(global) / double(m);
                ++nonEmpty;
            }
        }
        if (nonEmpty == 0 || gain < AUTO_BRICK_GAIN * double(nonEmpty))
            buildMajorants(MajorantMode::Global);
        return;
    }
    buildMajorants(m_options.majorant);
}

void GridMedium::buildMajorants(MajorantMode mode) {
    const int r = m_spec.resolution;
    if (mode == MajorantMode::Global) {
        m_cells = 1;
        m_cellSize = m_spec.voxelSize * float(r);
    } else {
        m_cells = (r + BRICK - 1) / BRICK;
        m_cellSize = m_spec.voxelSize * float(BRICK);
    }
    const int per = mode == MajorantMode::Global ? r : BRICK;
    m_majorant.assign(size_t(m_cells) * m_cells * m_cells * 4, 0.f);
    m_globalMajorant = {0.f, 0.f, 0.f, 0.f};
    for (int z = 0; z < r; ++z)
        for (int y = 0; y < r; ++y)
            for (int x = 0; x < r; ++x) {
                const size_t v = (size_t(z) * r + y) * r + x;
                const size_t cell =
                    (size_t(z / per) * m_cells + size_t(y / per)) * m_cells + size_t(x / per);
                for (int c = 0; c < 3; ++c) {
                    const float st = m_sigmaT[c][v];
                    float& m = m_majorant[cell * 4 + size_t(c)];
                    m = std::max(m, st);
                    float& any = m_majorant[cell * 4 + size_t(ANY_CHANNEL)];
                    any = std::max(any, st);
                    for (size_t k : {size_t(c), size_t(ANY_CHANNEL)})
                        m_globalMajorant[k] = std::max(m_globalMajorant[k], st);
                }
            }
}

}  // namespace lucent::reference
